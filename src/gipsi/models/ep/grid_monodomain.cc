/// @file
/// Finite-difference (finite-volume on the dual grid) monodomain object.

#include "gipsi/models/ep/grid_monodomain.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "gipsi/base/error.h"
#include "gipsi/base/units.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/models/ep/ep_tissue_json.h"

namespace gipsi {
namespace {

// The grid's nodes, surface triangles and surface groups (the box generator's, without tets).
std::shared_ptr<const Mesh> GridMesh(const CartesianGrid& grid) {
  Mesh mesh = MakeTetBox(grid.min, grid.max, grid.cells);
  mesh.tets.resize(4, 0);
  std::erase_if(mesh.groups, [](const MeshGroup& g) { return g.dim == 3; });
  return std::make_shared<const Mesh>(std::move(mesh));
}

}  // namespace

GridMonodomain::GridMonodomain(std::string name, const CartesianGrid& grid, EpTissueParams params)
    : EpTissue(std::move(name), std::move(params)), grid_(grid) {
  if (!params_.lumped_mass)
    throw InputError(
        "GridMonodomain has a diagonal (lumped) mass only: remove \"mass\": \"consistent\"");
  if (params_.fibre_rule)
    throw InputError(
        "GridMonodomain needs fibres along a grid axis (\"fibres\": {\"direction\": [1, 0, "
        "0]}); rule-based fibres need Monodomain on tets");
  if (params_.anisotropic()) {
    if (!params_.fibre)
      throw InputError(
          "the conductivity is anisotropic (longitudinal != transverse), so the object needs a "
          "fibre direction along a grid axis, e.g. \"fibres\": {\"direction\": [1, 0, 0]}");
    const Vec3 f = params_.fibre->normalized();
    if (f.cwiseAbs().maxCoeff() < 1 - 1e-12)
      throw InputError(fmt::format(
          "fibres ({:.4g}, {:.4g}, {:.4g}) are not along a grid axis; GridMonodomain's 7-point "
          "stencil needs a conductivity diagonal in x, y, z (use Monodomain on tets for other "
          "directions)",
          f.x(), f.y(), f.z()));
  }
  auto mesh = GridMesh(grid_);
  SetGeometry(mesh, MakeBoundary(*mesh));
  InitTissue();
  Assemble();
}

void GridMonodomain::Assemble() {
  const Vec3 h = 1e3 * grid_.spacing();  // mm
  const Vec3 f = params_.fibre.value_or(Vec3::UnitX()).normalized();
  const double dl = params_.diffusivity_longitudinal();
  const double dt = params_.diffusivity_transverse();
  const Vec3 d = (dt + (dl - dt) * f.array().square()).matrix();  // diagonal D [mm²/ms]
  const std::array<int, 3>& n = grid_.cells;
  // Dual length of node index `idx` on axis a: a half cell at the domain boundary.
  auto dual = [&](int a, int idx) { return (idx == 0 || idx == n[a]) ? 0.5 * h[a] : h[a]; };
  const Index num = grid_.num_nodes();
  VecX volume(num);
  std::vector<Eigen::Triplet<double, int>> entries;
  entries.reserve(static_cast<std::size_t>(7 * num));
  for (int k = 0; k <= n[2]; ++k)
    for (int j = 0; j <= n[1]; ++j)
      for (int i = 0; i <= n[0]; ++i) {
        const std::array<int, 3> idx = {i, j, k};
        const auto p = static_cast<int>(grid_.node(i, j, k));
        volume[p] = dual(0, i) * dual(1, j) * dual(2, k);
        for (int a = 0; a < 3; ++a) {
          if (idx[a] == n[a]) continue;  // no neighbour beyond the last node
          std::array<int, 3> next = idx;
          ++next[a];
          const auto q = static_cast<int>(grid_.node(next[0], next[1], next[2]));
          const int b = (a + 1) % 3, c = (a + 2) % 3;
          const double coupling = d[a] * dual(b, idx[b]) * dual(c, idx[c]) / h[a];
          entries.emplace_back(p, p, coupling);
          entries.emplace_back(q, q, coupling);
          entries.emplace_back(p, q, -coupling);
          entries.emplace_back(q, p, -coupling);
        }
      }
  SparseMatrix stiffness(static_cast<int>(num), static_cast<int>(num));
  stiffness.setFromTriplets(entries.begin(), entries.end());
  SetDiffusionOperator(std::move(stiffness), std::move(volume));
}

PointMap GridMonodomain::MapFromNodes(const Points& targets) const {
  const Vec3 h = grid_.spacing();
  Eigen::Matrix4Xi indices(4, targets.cols());
  Eigen::Matrix4Xd weights(4, targets.cols());
  double max_distance = 0;
  for (Index t = 0; t < targets.cols(); ++t) {
    const Vec3 x = targets.col(t);
    if (!x.allFinite()) throw InputError(fmt::format("target point {} is not finite", t));
    std::array<int, 3> cell{};
    Vec3 local;
    for (int a = 0; a < 3; ++a) {
      const double s = (x[a] - grid_.min[a]) / h[a];
      cell[a] = std::clamp(static_cast<int>(std::floor(s)), 0, grid_.cells[a] - 1);
      local[a] = std::clamp(s - cell[a], 0.0, 1.0);
    }
    const Vec3 reproduced = grid_.min + h.cwiseProduct(Vec3(cell[0], cell[1], cell[2]) + local);
    max_distance = std::max(max_distance, (reproduced - x).norm());
    // Kuhn simplex: walk from the cell's low corner along the axes in decreasing local
    // coordinate; the weights are the successive differences of the sorted coordinates.
    std::array<int, 3> order = {0, 1, 2};
    std::sort(order.begin(), order.end(), [&](int a, int b) { return local[a] > local[b]; });
    std::array<int, 3> corner = cell;
    double previous = 1;
    for (int m = 0; m < 4; ++m) {
      const double coordinate = m < 3 ? local[order[static_cast<std::size_t>(m)]] : 0.0;
      indices(m, t) = static_cast<int>(grid_.node(corner[0], corner[1], corner[2]));
      weights(m, t) = previous - coordinate;
      previous = coordinate;
      if (m < 3) ++corner[static_cast<std::size_t>(order[static_cast<std::size_t>(m)])];
    }
  }
  return PointMap::FromWeights(std::move(indices), std::move(weights), max_distance);
}

void RegisterGridMonodomain(TypeRegistry& registry) {
  registry.objects.Register(
      "GridMonodomain",
      [](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        CheckEpTissueKeys(ctx, {"grid"});
        const JsonNode& p = ctx.params;
        if (auto domain = p.Find("domain"))
          domain->Fail("GridMonodomain builds its own grid (key \"grid\"); remove \"domain\"");
        const JsonNode g = p.At("grid");
        g.CheckKeys({"min", "max", "cells", "spacing"});
        CartesianGrid grid;
        grid.min = g.Vector3("min");
        grid.max = g.Vector3("max");
        if (!(grid.max.array() > grid.min.array()).all())
          g.At("max").Expected("a corner beyond \"min\" on every axis");
        if (g.Has("cells") == g.Has("spacing"))
          g.Fail("give exactly one of \"cells\" (3 integers) or \"spacing\" (a length, m)");
        if (auto cells = g.Find("cells")) {
          const auto c = cells->AsInts();
          if (c.size() != 3 || *std::min_element(c.begin(), c.end()) < 1 ||
              *std::max_element(c.begin(), c.end()) > 100000)
            cells->Expected("3 integers in [1, 100000]");
          grid.cells = {static_cast<int>(c[0]), static_cast<int>(c[1]), static_cast<int>(c[2])};
        } else {
          const JsonNode s = g.At("spacing");
          const double h = ReadPositiveQuantity(s, "m");
          for (int a = 0; a < 3; ++a) {
            const double cells = (grid.max[a] - grid.min[a]) / h;
            if (cells > 100000) s.Expected("a spacing giving at most 100000 cells per axis");
            grid.cells[static_cast<std::size_t>(a)] =
                std::max(1, static_cast<int>(std::lround(cells)));
          }
        }
        if (double(grid.num_nodes()) > kMaxGeneratedElements)
          g.Fail(fmt::format("{} x {} x {} cells would make more than {:.0e} grid nodes",
                             grid.cells[0], grid.cells[1], grid.cells[2], kMaxGeneratedElements));
        EpTissueParams params = ParseEpTissueParams(ctx);
        try {
          return std::make_unique<GridMonodomain>(ctx.name, grid, std::move(params));
        } catch (const InputError& e) {
          p.Fail(e.what());
        }
      },
      "cardiac monodomain by finite differences on a regular Cartesian grid");
}

}  // namespace gipsi
