/// @file
/// Fibres on ellipsoidal coordinates (Land et al. 2015, problem 3).

#include "gipsi/models/fibres/ellipsoidal_fibres.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "gipsi/models/fibres/rule_based_fibres.h"

namespace gipsi {

EllipsoidalFibre EllipsoidalFibreAt(const EllipsoidalFibreRule& rule, const Vec3& point) {
  const Vec3 d = point - rule.centre;
  const double rho = std::hypot(d.x(), d.y());
  auto radii = [&rule](double t) {
    return std::pair{rule.endo_short + (rule.epi_short - rule.endo_short) * t,
                     rule.endo_long + (rule.epi_long - rule.endo_long) * t};
  };
  // The family's ellipsoid through the point: g(t) = ρ²/r_s² + z²/r_l² − 1 = 0. Both radii grow
  // with t, so g falls; bisect on a bracket wide enough for points just outside the wall.
  auto g = [&](double t) {
    const auto [rs, rl] = radii(t);
    return rho * rho / (rs * rs) + d.z() * d.z() / (rl * rl) - 1;
  };
  // At most one wall thickness beyond each side, keeping both radii positive (epi > endo, as
  // ParseEllipsoidalFibreRule checks).
  double lo = std::max({-1.0, -0.9 * rule.endo_short / (rule.epi_short - rule.endo_short),
                        -0.9 * rule.endo_long / (rule.epi_long - rule.endo_long)});
  double hi = 2;
  double t = 0.5;
  if (g(lo) <= 0) {
    t = lo;
  } else if (g(hi) >= 0) {
    t = hi;
  } else {
    for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
      const double mid = 0.5 * (lo + hi);
      (g(mid) > 0 ? lo : hi) = mid;
    }
    t = 0.5 * (lo + hi);
  }
  const auto [rs, rl] = radii(t);
  // u in [−π, 0): cos u = z/r_l, sin u = −ρ/r_s (the point's own ellipsoid, so they agree).
  const double u = std::atan2(-rho / rs, std::clamp(d.z() / rl, -1.0, 1.0));
  // sin u < 0: cos v = −x/ρ, sin v = −y/ρ; on the axis, v = 0.
  const double v = rho > 0 ? std::atan2(-d.y(), -d.x()) : 0.0;
  const Vec3 dxdu(rs * std::cos(u) * std::cos(v), rs * std::cos(u) * std::sin(v),
                  -rl * std::sin(u));
  Vec3 dxdv(-std::sin(v), std::cos(v), 0);  // ∂x/∂v / (r_s sin u) up to its sign
  dxdv *= std::sin(u) < 0 ? -1.0 : 1.0;
  const double s = std::clamp(t, 0.0, 1.0);
  const double alpha =
      (rule.endo_angle + (rule.epi_angle - rule.endo_angle) * s) * std::numbers::pi / 180;
  EllipsoidalFibre out;
  out.t = t;
  out.fibre = (std::sin(alpha) * dxdu.normalized() + std::cos(alpha) * dxdv).normalized();
  return out;
}

Points EllipsoidalFibresAtCentroids(const Mesh& mesh, const EllipsoidalFibreRule& rule) {
  Points fibres(3, mesh.num_tets());
  for (Index e = 0; e < mesh.num_tets(); ++e) {
    Vec3 centroid = Vec3::Zero();
    for (int a = 0; a < 4; ++a) centroid += 0.25 * mesh.nodes.col(mesh.tets(a, e));
    fibres.col(e) = EllipsoidalFibreAt(rule, centroid).fibre;
  }
  return fibres;
}

EllipsoidalFibreRule ParseEllipsoidalFibreRule(const JsonNode& node) {
  node.CheckKeys({"rule", "endo", "epi", "centre", "endo_angle", "epi_angle"});
  if (node.At("rule").AsChoice({"ellipsoidal"}) != "ellipsoidal")
    node.At("rule").Expected("\"ellipsoidal\"");
  EllipsoidalFibreRule rule;
  auto radii = [&node](const char* key, double& short_radius, double& long_radius) {
    const JsonNode at = node.At(key);
    const std::vector<double> r = at.AsNumbers();
    if (r.size() != 2 || !(r[0] > 0) || !(r[1] > 0))
      at.Expected("[short radius, long radius], both > 0 (m)");
    short_radius = r[0];
    long_radius = r[1];
  };
  radii("endo", rule.endo_short, rule.endo_long);
  radii("epi", rule.epi_short, rule.epi_long);
  if (!(rule.epi_short > rule.endo_short && rule.epi_long > rule.endo_long))
    node.At("epi").Expected("radii larger than the endocardium's (the wall lies between them)");
  rule.centre = node.Vector3("centre", rule.centre);
  ParseHelixAngles(node, rule.endo_angle, rule.epi_angle);
  return rule;
}

}  // namespace gipsi
