#pragma once
/// @file
/// The volume enclosed by an oriented triangle surface and its gradient with respect to the
/// vertex positions — what couples a deforming cavity (a ventricle) to a lumped blood model.
/// Closed surfaces use the divergence theorem: V = Σ_t (1/6) x0 · (x1 × x2) (positive when the
/// triangles are oriented with outward normals). An open surface (an endocardium cut at the
/// base) is closed by capping each boundary loop with a fan of triangles to the loop's centroid;
/// the centroid moves with the loop, so its contribution to the gradient is shared equally among
/// the loop's vertices.

#include <utility>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/boundary.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A cavity's wall as its own surface: boundary faces of a tissue, renumbered. Plain struct.
struct CavitySurface {
  std::vector<int> nodes;  ///< domain node of each surface vertex, in order of first use
  /// 3 by F over the surface vertices, each face reversed so that it faces out of the cavity
  /// (a boundary's normals point out of the tissue, into the cavity): the enclosed volume is
  /// then positive.
  Triangles triangles;
};

/// The surface of the cavity bounded by `faces` (indices into `boundary`'s triangles).
CavitySurface MakeCavitySurface(const BoundarySurface& boundary, const std::vector<int>& faces);

/// Precomputed capping of one surface. Immutable; copyable.
class EnclosedVolume {
 public:
  /// `triangles` (3 by T) index vertices 0..num_vertices−1 and must be consistently oriented.
  /// Throws InputError if the boundary is not a set of simple loops (a non-manifold edge or
  /// vertex, or inconsistent orientation).
  EnclosedVolume(const Triangles& triangles, Index num_vertices);

  /// Number of boundary loops capped (0 for a closed surface).
  [[nodiscard]] Index num_loops() const { return static_cast<Index>(loops_.size()); }
  /// Each boundary loop as its half-edges (a → b, vertex indices, as oriented in the surface).
  [[nodiscard]] const std::vector<std::vector<std::pair<int, int>>>& loops() const {
    return loops_;
  }
  /// The surface's triangles (3 by T, vertex indices).
  [[nodiscard]] const Triangles& triangles() const { return triangles_; }
  /// Enclosed volume for vertex positions `x` (3 by num_vertices) [m³ if x in m]. If
  /// `gradient` is not null it is resized to 3 by num_vertices and receives ∂V/∂x.
  double Compute(const Points& x, Points* gradient = nullptr) const;

 private:
  Triangles triangles_;
  Index num_vertices_;
  /// Each loop: its boundary half-edges (a → b, as oriented in the surface).
  std::vector<std::vector<std::pair<int, int>>> loops_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
