#pragma once
/// @file
/// `GridMonodomain`: cardiac bioelectricity by finite differences on a regular Cartesian grid —
/// the discretisation of many cardiac codes, and GiPSi's example of an object whose domain is
/// not a mesh. Cell models, splitting, stimuli, clamps, activation maps and fields are those of
/// `EpTissue` (ep_tissue.h); only the diffusion operator differs.
///
/// The grid has (n_x + 1)(n_y + 1)(n_z + 1) nodes with spacings h_a. Each node owns the
/// box-shaped control volume of the dual grid (half-width at the domain boundary), and the
/// flux between neighbours i, j along axis a is D_a A_ij (V_j − V_i)/h_a, A_ij the dual face
/// area. So K is the 7-point Laplacian (second order, symmetric, rows summing to zero), no-flux
/// boundaries hold by construction, and M is diagonal (the control volumes). The conductivity
/// must be diagonal in the grid axes: fibres along x, y or z (a rotated tensor needs the 19-point
/// stencil, not implemented; use `Monodomain` on tets).
///
/// Geometry: the domain "mesh" holds the grid nodes and the box's surface triangles (the
/// boundary and display geometry; groups xmin … zmax as for the box generator), no tets. Other
/// objects read its node fields through `MapFromNodes`, which interpolates linearly on the
/// six Kuhn simplices of each grid cell (no search: the cell follows from the coordinates).

#include <array>
#include <memory>
#include <string>

#include "gipsi/base/export.h"
#include "gipsi/core/registry.h"
#include "gipsi/models/ep/ep_tissue.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A regular grid [min, max] with `cells` cells per axis (scene units, m). Plain struct.
struct CartesianGrid {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Ones();
  std::array<int, 3> cells = {1, 1, 1};
  [[nodiscard]] Vec3 spacing() const {
    return (max - min).cwiseQuotient(Vec3(cells[0], cells[1], cells[2]));
  }
  [[nodiscard]] Index num_nodes() const {
    return Index(cells[0] + 1) * (cells[1] + 1) * (cells[2] + 1);
  }
  /// Index of node (i, j, k): i + (n_x + 1)(j + (n_y + 1) k).
  [[nodiscard]] Index node(int i, int j, int k) const {
    return i + Index(cells[0] + 1) * (j + Index(cells[1] + 1) * k);
  }
};

/// Not copyable or movable (a SimObject).
class GridMonodomain final : public EpTissue {
 public:
  /// Throws InputError for an empty or inverted grid, fibres not along a grid axis, an
  /// anisotropic conductivity without fibres, consistent mass, or a stimulus/clamp region that
  /// selects no node.
  GridMonodomain(std::string name, const CartesianGrid& grid, EpTissueParams params);

  [[nodiscard]] std::string_view type_name() const override { return "GridMonodomain"; }
  [[nodiscard]] const Points& domain_positions() const override { return domain().nodes; }
  [[nodiscard]] const CartesianGrid& grid() const { return grid_; }
  /// Linear interpolation on the Kuhn simplices of the grid cell holding each target (targets
  /// outside are clamped to the grid; max_distance() reports how far).
  [[nodiscard]] PointMap MapFromNodes(const Points& targets) const override;

 private:
  void Assemble();

  CartesianGrid grid_;
};

/// Registers "GridMonodomain" (keys in docs/scene-format.md).
void RegisterGridMonodomain(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
