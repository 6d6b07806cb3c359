/// @file
/// Transmural rule-based fibres.

#include "gipsi/models/fibres/rule_based_fibres.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/geometry/region_json.h"
#include "gipsi/numerics/p1_scalar.h"

namespace gipsi {
namespace {

// Solves K e = 0 with e fixed on the Dirichlet nodes: K_ff e_f = −K_fd e_d by CHOLMOD.
VecX SolveLaplace(const SparseMatrix& k, const std::vector<double>& fixed_value,
                  const std::vector<char>& is_fixed) {
  const Index n = k.rows();
  std::vector<int> free_index(static_cast<std::size_t>(n), -1);
  int num_free = 0;
  for (Index i = 0; i < n; ++i)
    if (!is_fixed[static_cast<std::size_t>(i)])
      free_index[static_cast<std::size_t>(i)] = num_free++;
  std::vector<Eigen::Triplet<double, int>> entries;
  VecX rhs = VecX::Zero(num_free);
  for (int col = 0; col < k.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(k, col); it; ++it) {
      const int fr = free_index[static_cast<std::size_t>(it.row())];
      if (fr < 0) continue;
      const int fc = free_index[static_cast<std::size_t>(col)];
      if (fc >= 0)
        entries.emplace_back(fr, fc, it.value());
      else
        rhs[fr] -= it.value() * fixed_value[static_cast<std::size_t>(col)];
    }
  SparseMatrix kff(num_free, num_free);
  kff.setFromTriplets(entries.begin(), entries.end());
  kff.makeCompressed();
  LinearSolverOptions options;
  options.type = "cholmod";
  options.tolerance = 1e-10;
  auto solver = MakeLinearSolver(options);
  solver->AnalyzePattern(kff);
  VecX free_solution = VecX::Zero(num_free);
  if (!solver->Factorize(kff) || !solver->Solve(rhs, free_solution).converged)
    throw InputError(
        "the transmural Laplace problem could not be solved (is every part of the wall "
        "connected to the endocardium or the epicardium?)");
  VecX e(n);
  for (Index i = 0; i < n; ++i) {
    const int f = free_index[static_cast<std::size_t>(i)];
    e[i] = f >= 0 ? free_solution[f] : fixed_value[static_cast<std::size_t>(i)];
  }
  return e;
}

}  // namespace

FibreField MakeTransmuralFibres(const Mesh& mesh, const TransmuralFibreRule& rule) {
  if (mesh.num_tets() == 0) throw InputError("rule-based fibres need a tetrahedral mesh");
  const std::vector<int> endo = SelectNodes(rule.endo, mesh);
  const std::vector<int> epi = SelectNodes(rule.epi, mesh);
  if (endo.empty()) throw InputError("the fibre rule's endo region selects no node");
  if (epi.empty()) throw InputError("the fibre rule's epi region selects no node");
  const auto n = static_cast<std::size_t>(mesh.num_nodes());
  std::vector<char> is_fixed(n, 0);
  std::vector<double> value(n, 0.0);
  for (int i : endo) is_fixed[static_cast<std::size_t>(i)] = 1;
  for (int i : epi) {
    if (is_fixed[static_cast<std::size_t>(i)])
      throw InputError(fmt::format("node {} is in both the endo and the epi region", i));
    is_fixed[static_cast<std::size_t>(i)] = 1;
    value[static_cast<std::size_t>(i)] = 1.0;
  }
  const P1ScalarOperators ops = AssembleP1Scalar(
      mesh.nodes, mesh.tets, 1.0, [](Index) -> Mat3 { return Mat3::Identity(); }, false);
  return TransmuralFibresFrom(mesh, rule, SolveLaplace(ops.stiffness, value, is_fixed));
}

FibreField TransmuralFibresFrom(const Mesh& mesh, const TransmuralFibreRule& rule,
                                VecX transmural) {
  GIPSI_CHECK(transmural.size() == mesh.num_nodes(), "{} transmural values for {} nodes",
              transmural.size(), mesh.num_nodes());
  FibreField out;
  out.transmural = std::move(transmural);
  const Index ne = mesh.num_tets();
  out.fibre.resize(3, ne);
  out.sheet.resize(3, ne);
  const Vec3 k = rule.axis.normalized();
  for (Index e = 0; e < ne; ++e) {
    const Eigen::Matrix<double, 4, 3> grad = P1Gradients(mesh.nodes, mesh.tets, e);
    Vec3 g = Vec3::Zero();
    double centroid = 0;
    for (int a = 0; a < 4; ++a) {
      const double ea = out.transmural[mesh.tets(a, e)];
      g += ea * grad.row(a).transpose();
      centroid += ea / 4;
    }
    // A tet with all four nodes on one surface has ∇e = 0: use the direction away from the
    // long axis through its centroid (outward for a ventricle around the axis).
    Vec3 t = g;
    if (t.norm() == 0) {
      Vec3 p = Vec3::Zero();
      for (int a = 0; a < 4; ++a) p += mesh.nodes.col(mesh.tets(a, e)) / 4;
      t = p - p.dot(k) * k;
      if (t.norm() == 0) t = Vec3::UnitX();
    }
    t.normalize();
    out.fibre.col(e) = TransmuralFibreAt(rule, t, centroid);
    out.sheet.col(e) = t;
  }
  return out;
}

Vec3 TransmuralFibreAt(const TransmuralFibreRule& rule, const Vec3& t, double e) {
  constexpr double kDegree = std::numbers::pi / 180;
  const Vec3 k = rule.axis.normalized();
  Vec3 c = k.cross(t);
  if (c.norm() < 1e-6) {
    for (int a = 0; a < 3 && c.norm() < 1e-6; ++a) c = Vec3::Unit(a).cross(t);
  }
  c.normalize();
  const Vec3 l = t.cross(c);
  const double alpha = kDegree * (rule.endo_angle + (rule.epi_angle - rule.endo_angle) * e);
  return std::cos(alpha) * c + std::sin(alpha) * l;
}

TransmuralFibreRule ParseTransmuralFibreRule(const JsonNode& node) {
  node.CheckKeys({"rule", "endo", "epi", "axis", "endo_angle", "epi_angle"});
  if (node.At("rule").AsChoice({"transmural"}) != "transmural")
    node.At("rule").Expected("\"transmural\"");
  TransmuralFibreRule rule;
  rule.endo = ParseRegion(node.At("endo"));
  rule.epi = ParseRegion(node.At("epi"));
  rule.axis = node.Vector3("axis", rule.axis);
  if (rule.axis.norm() == 0) node.At("axis").Expected("a non-zero vector");
  ParseHelixAngles(node, rule.endo_angle, rule.epi_angle);
  return rule;
}

void ParseHelixAngles(const JsonNode& node, double& endo, double& epi) {
  endo = node.Number("endo_angle", endo);
  epi = node.Number("epi_angle", epi);
  for (const char* key : {"endo_angle", "epi_angle"})
    if (auto a = node.Find(key); a && std::abs(a->AsNumber()) > 90)
      a->Expected("a helix angle in degrees within [-90, 90]");
}

}  // namespace gipsi
