#include "gipsi/models/fem/quadratic_volume.h"

#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/models/fem/fem_geometry.h"
#include "gipsi/models/fem/quadratic_tets.h"

namespace gipsi {
namespace {

using Face = Eigen::Matrix<double, 3, 6>;

/// The shape functions and their parameter derivatives at the rule's points (fixed).
struct FaceRule {
  std::vector<Eigen::Matrix<double, 6, 1>> n;
  std::vector<Eigen::Matrix<double, 6, 2>> dn;
  std::vector<double> w;  // the rule's weight × the reference triangle's area (1/2) / 3
  FaceRule() {
    const TriangleQuadrature& rule = TriangleRuleDegree4();
    for (std::size_t q = 0; q < rule.points.size(); ++q) {
      n.push_back(QuadraticTriangleShape(rule.points[q]));
      dn.push_back(QuadraticTriangleParamDerivatives(rule.points[q]));
      w.push_back(rule.weights[q] / 6);
    }
  }
};

const FaceRule& Rule() {
  static const FaceRule rule;
  return rule;
}

}  // namespace

double QuadraticTriangleVolume(const Face& x, const Vec3& origin, Face* gradient) {
  const FaceRule& rule = Rule();
  double volume = 0;
  if (gradient != nullptr) gradient->setZero();
  for (std::size_t q = 0; q < rule.w.size(); ++q) {
    const Vec3 y = x * rule.n[q] - origin;
    const Vec3 t1 = x * rule.dn[q].col(0), t2 = x * rule.dn[q].col(1);
    const Vec3 normal = t1.cross(t2);
    volume += rule.w[q] * y.dot(normal);
    if (gradient == nullptr) continue;
    // ∂(y · (t1 × t2))/∂x_k = N_k (t1 × t2) + N_k,ξ (t2 × y) + N_k,η (y × t1).
    const Vec3 c1 = t2.cross(y), c2 = y.cross(t1);
    for (int k = 0; k < 6; ++k)
      gradient->col(k) +=
          rule.w[q] * (rule.n[q][k] * normal + rule.dn[q](k, 0) * c1 + rule.dn[q](k, 1) * c2);
  }
  return volume;
}

QuadraticEnclosedVolume::QuadraticEnclosedVolume(QuadraticTriangles faces,
                                                 std::vector<std::vector<RimEdge>> loops,
                                                 Index num_nodes, const Vec3& origin)
    : faces_(std::move(faces)), loops_(std::move(loops)), num_nodes_(num_nodes), origin_(origin) {
  GIPSI_CHECK((faces_.array() >= 0).all() && (faces_.array() < num_nodes_).all(),
              "QuadraticEnclosedVolume: a face refers to a node outside 0..{}", num_nodes_ - 1);
  for (const auto& loop : loops_) GIPSI_CHECK(!loop.empty(), "QuadraticEnclosedVolume: empty rim");
}

double QuadraticEnclosedVolume::Compute(const Points& x, Points* gradient) const {
  GIPSI_CHECK(x.cols() == num_nodes_);
  if (gradient != nullptr) gradient->setZero(3, num_nodes_);
  double volume = 0;
  Face xf, g;
  Face* gp = gradient != nullptr ? &g : nullptr;
  for (Index f = 0; f < faces_.cols(); ++f) {
    for (int k = 0; k < 6; ++k) xf.col(k) = x.col(faces_(k, f));
    volume += QuadraticTriangleVolume(xf, origin_, gp);
    if (gp != nullptr)
      for (int k = 0; k < 6; ++k) gradient->col(faces_(k, f)) += g.col(k);
  }
  for (const auto& loop : loops_) {
    Vec3 c = Vec3::Zero();
    for (const RimEdge& e : loop) c += x.col(e.a);
    c /= static_cast<double>(loop.size());
    Vec3 dc = Vec3::Zero();  // ∂V/∂c, shared by the loop's vertices
    for (const RimEdge& e : loop) {
      // The cap triangle (b, a, c) runs the rim edge backwards, closing the surface; its
      // middle nodes are the rim edge's and the midpoints of its straight edges to c.
      const Vec3 xa = x.col(e.a), xb = x.col(e.b);
      xf.col(0) = xb;
      xf.col(1) = xa;
      xf.col(2) = c;
      xf.col(3) = x.col(e.middle);
      xf.col(4) = 0.5 * (xa + c);
      xf.col(5) = 0.5 * (xb + c);
      volume += QuadraticTriangleVolume(xf, origin_, gp);
      if (gp == nullptr) continue;
      gradient->col(e.b) += g.col(0) + 0.5 * g.col(5);
      gradient->col(e.a) += g.col(1) + 0.5 * g.col(4);
      gradient->col(e.middle) += g.col(3);
      dc += g.col(2) + 0.5 * (g.col(4) + g.col(5));
    }
    if (gp != nullptr)
      for (const RimEdge& e : loop) gradient->col(e.a) += dc / static_cast<double>(loop.size());
  }
  return volume;
}

FaceHessian QuadraticEnclosedVolume::Hessian(Index f, const Points& x) const {
  const FaceRule& rule = Rule();
  Face xf;
  for (int k = 0; k < 6; ++k) xf.col(k) = x.col(faces_(k, f));
  FaceHessian h = FaceHessian::Zero();
  for (std::size_t q = 0; q < rule.w.size(); ++q) {
    const Eigen::Matrix<double, 6, 1>& n = rule.n[q];
    const Eigen::Matrix<double, 6, 2>& dn = rule.dn[q];
    const Vec3 y = xf * n - origin_;
    const Mat3 t1 = CrossMatrix(xf * dn.col(0)), t2 = CrossMatrix(xf * dn.col(1));
    const Mat3 yx = CrossMatrix(y);
    // ∂/∂x_l of the gradient's terms N_k (t1 × t2) + N_k,ξ (t2 × y) + N_k,η (y × t1).
    for (int l = 0; l < 6; ++l) {
      const Mat3 d_normal = -dn(l, 0) * t2 + dn(l, 1) * t1;
      const Mat3 d_c1 = -dn(l, 1) * yx + n[l] * t2;
      const Mat3 d_c2 = -n[l] * t1 + dn(l, 0) * yx;
      for (int k = 0; k < 6; ++k)
        h.block<3, 3>(3 * k, 3 * l) +=
            rule.w[q] * (n[k] * d_normal + dn(k, 0) * d_c1 + dn(k, 1) * d_c2);
    }
  }
  return h;
}

}  // namespace gipsi
