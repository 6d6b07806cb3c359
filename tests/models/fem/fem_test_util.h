#pragma once
// Shared set-up for the FEM tests: laws from JSON, boxes, and boundary selections.

#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "gipsi/base/json_node.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/models/fem/fem_solid.h"

namespace gipsi::testing {

/// A solid law from its JSON description, e.g. R"({"law": "Linear", ...})".
inline std::shared_ptr<const SolidMaterial> Law(const std::string& json) {
  static TypeRegistry& registry = []() -> TypeRegistry& {
    static TypeRegistry r;
    RegisterSolidLaws(r);
    return r;
  }();
  const JsonDocument doc = JsonDocument::Parse(json, "test.json");
  return registry.CreateMaterialAs<SolidMaterial>(doc.root(), "solid");
}

/// Every law at moderate stiffness (E ≈ 10 kPa scale), for property tests over all laws.
inline std::vector<std::string> AllLaws() {
  return {
      R"({"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3})",
      R"({"law": "Corotational", "youngs_modulus": 1e4, "poisson_ratio": 0.3})",
      R"({"law": "StVenantKirchhoff", "youngs_modulus": 1e4, "poisson_ratio": 0.3})",
      R"({"law": "NeoHookean", "youngs_modulus": 1e4, "poisson_ratio": 0.3})",
      R"({"law": "Guccione", "C": 2000, "bf": 8, "bt": 2, "bfs": 4, "bulk_modulus": 5e4})",
  };
}

/// A unit box of cells³ cells whose interior nodes are moved randomly by up to 20 % of a cell.
inline std::shared_ptr<const Mesh> DistortedBox(int cells, unsigned seed = 7) {
  Mesh mesh = MakeTetBox(Vec3::Zero(), Vec3::Ones(), {cells, cells, cells});
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.2 / cells, 0.2 / cells);
  for (Index i = 0; i < mesh.num_nodes(); ++i) {
    const Vec3 p = mesh.nodes.col(i);
    const bool interior = (p.array() > 1e-12).all() && (p.array() < 1 - 1e-12).all();
    if (interior) mesh.nodes.col(i) += Vec3(jitter(rng), jitter(rng), jitter(rng));
  }
  return std::make_shared<const Mesh>(std::move(mesh));
}

/// Boundary vertices whose rest position satisfies `pred`.
inline std::vector<Index> VerticesWhere(const SimObject& object,
                                        const std::function<bool(const Vec3&)>& pred) {
  std::vector<Index> out;
  const auto& v2n = object.boundary().vertex_to_node;
  for (std::size_t j = 0; j < v2n.size(); ++j)
    if (pred(object.domain().nodes.col(v2n[j]))) out.push_back(static_cast<Index>(j));
  return out;
}

/// Boundary faces whose three rest vertices satisfy `pred`.
inline std::vector<Index> FacesWhere(const SimObject& object,
                                     const std::function<bool(const Vec3&)>& pred) {
  std::vector<Index> out;
  const BoundarySurface& b = object.boundary();
  for (Index f = 0; f < b.num_triangles(); ++f) {
    bool all = true;
    for (int i = 0; i < 3; ++i)
      all = all && pred(object.domain().nodes.col(
                       b.vertex_to_node[static_cast<std::size_t>(b.triangles(i, f))]));
    if (all) out.push_back(f);
  }
  return out;
}

/// Parameters for an accurate solve: direct linear solver, tight Newton tolerance, no gravity.
inline FemParams AccurateParams(const std::string& law_json, ImplicitSchemeKind scheme) {
  FemParams p;
  p.material = Law(law_json);
  p.gravity = Vec3::Zero();
  p.scheme = scheme;
  // Residual 1e-10 of the load scale: above the round-off floor of the force assembly
  // (~1e-13 of the element force magnitudes) on every mesh the tests use.
  p.newton.tolerance = 1e-10;
  p.linear_solver.type = "ldlt";
  return p;
}

}  // namespace gipsi::testing
