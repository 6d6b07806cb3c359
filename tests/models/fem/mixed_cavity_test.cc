// MixedSolid's cavities: the volume of curved (6-node) faces against the truncated ellipsoid's,
// its derivatives against finite differences, and a cavity coupled to a blood law, whose
// pressure must be the one that, prescribed, gives the blood's volume. The heart with this
// muscle is in tests/models/heart/heart_mixed_test.cc.

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <fmt/format.h>

#include "gipsi/geometry/enclosed_volume.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/region.h"
#include "gipsi/models/fem/mixed_solid.h"
#include "gipsi/models/fem/quadratic_volume.h"
#include "models/fem/fem_test_util.h"

namespace gipsi {
namespace {

using testing::Law;
using testing::VerticesWhere;

/// The volume of {x² + y² < a² (1 − z²/c²), z < z_b}: a truncated spheroid.
double TruncatedSpheroid(double a, double c, double zb) {
  return M_PI * a * a * ((zb + c) - (zb * zb * zb + c * c * c) / (3 * c * c));
}

MixedSolidParams CavityParams() {
  MixedSolidParams params;
  params.material = Law(R"({"law": "NeoHookean", "youngs_modulus": 3e4, "poisson_ratio": 0.45})");
  params.incompressible = true;
  params.newton.tolerance = 1e-10;
  params.newton.max_iterations = 40;
  params.cavities.push_back(CavitySpec{"lumen", GroupRegion{"endo"}});
  return params;
}

/// The heart's ventricle (metres), coarse; base held.
std::shared_ptr<const Mesh> Ventricle(double size, int order = 1) {
  EllipsoidShellSpec spec{.endo_short = 0.022,
                          .endo_long = 0.048,
                          .epi_short = 0.032,
                          .epi_long = 0.058,
                          .base_z = 0.012,
                          .mesh_size = size,
                          .order = order};
  return std::make_shared<const Mesh>(MakeEllipsoidShell(spec));
}

double ReadGlobal(const SimObject& object, const std::string& field) {
  Eigen::MatrixXd out(1, 1);
  object.ReadField(object.FindField(field), out);
  return out(0, 0);
}

void HoldBase(MixedSolid& solid) {
  for (Index v : VerticesWhere(solid, [](const Vec3& x) { return std::abs(x.z() - 0.012) < 1e-9; }))
    solid.boundary_conditions().Fix(v, kAllAxes);
}

// One 6-node triangle with curved edges: the gradient of (1/3) ∫ (x − o)·n dA against central
// differences (its error is O(ε²) of a cubic: 1e-9 relative), and the Hessian against
// differences of the gradient.
TEST(QuadraticVolume, TriangleGradientAndHessianMatchFiniteDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.2, 0.2);
  Eigen::Matrix<double, 3, 6> x;
  x << 0, 1, 0, 0.5, 0.5, 0, 0, 0, 1, 0, 0.5, 0.5, 0, 0, 0, 0, 0, 0;
  for (Index i = 0; i < x.size(); ++i) x.data()[i] += jitter(rng);
  const Vec3 origin(0.3, -0.2, 0.7);
  Eigen::Matrix<double, 3, 6> g;
  QuadraticTriangleVolume(x, origin, &g);
  const double h = 1e-5;
  double worst = 0;
  for (Index i = 0; i < x.size(); ++i) {
    Eigen::Matrix<double, 3, 6> xp = x, xm = x;
    xp.data()[i] += h;
    xm.data()[i] -= h;
    const double fd = (QuadraticTriangleVolume(xp, origin, nullptr) -
                       QuadraticTriangleVolume(xm, origin, nullptr)) /
                      (2 * h);
    worst = std::max(worst, std::abs(fd - g.data()[i]));
  }
  EXPECT_LT(worst, 1e-9 * g.norm());

  // The Hessian through a surface of this one face (no rim: the face's own term).
  QuadraticTriangles face(6, 1);
  for (int k = 0; k < 6; ++k) face(k, 0) = k;
  const QuadraticEnclosedVolume volume(face, {}, 6, origin);
  const Points xs = x;
  const FaceHessian hessian = volume.Hessian(0, xs);
  EXPECT_LT((hessian - hessian.transpose()).norm(), 1e-13 * hessian.norm());
  worst = 0;
  for (Index i = 0; i < xs.size(); ++i) {
    Points xp = xs, xm = xs, gp, gm;
    xp.data()[i] += h;
    xm.data()[i] -= h;
    volume.Compute(xp, &gp);
    volume.Compute(xm, &gm);
    const Eigen::Map<const Eigen::Matrix<double, 18, 1>> dp(gp.data()), dm(gm.data());
    worst = std::max(worst, ((dp - dm) / (2 * h) - hessian.col(i)).norm());
  }
  EXPECT_LT(worst, 1e-8 * hessian.norm());
}

// The cavity of the Gmsh ventricle: with straight edges its P2 volume is exactly the flat
// triangles' (EnclosedVolume, the FemSolid cavity's); with the second-order mesh's curved edges
// it is far closer to the truncated spheroid's (measured at 6 mm: 2.7e-4 against 1.8e-2).
TEST(MixedCavity, CurvedFacesEncloseTheTruncatedEllipsoidsCavity) {
  const double exact = TruncatedSpheroid(0.022, 0.048, 0.012);
  double error[2];
  for (int order : {1, 2}) {
    auto mesh = Ventricle(0.006, order);
    MixedSolid solid("lv", mesh, CavityParams());
    const double v = solid.CavityVolume(0);
    error[order - 1] = std::abs(v / exact - 1);
    EXPECT_EQ(ReadGlobal(solid, "lumen_volume"), v);
    if (order == 1) {
      const BoundarySurface& bnd = solid.boundary();
      const std::vector<int> endo = SelectBoundaryFaces(GroupRegion{"endo"}, *mesh, bnd);
      const CavitySurface surface = MakeCavitySurface(bnd, endo);
      Points x(3, static_cast<Index>(surface.nodes.size()));
      for (std::size_t k = 0; k < surface.nodes.size(); ++k)
        x.col(static_cast<Index>(k)) = mesh->nodes.col(surface.nodes[k]);
      const double flat =
          EnclosedVolume(surface.triangles, static_cast<Index>(surface.nodes.size())).Compute(x);
      EXPECT_NEAR(v, flat, 1e-13 * flat);
    }
  }
  fmt::print("[ info     ] cavity volume error: straight {:.2e}, curved {:.2e}\n", error[0],
             error[1]);
  EXPECT_LT(error[1], error[0] / 20);
}

// ∂V/∂x of the whole cavity, open rim and its moving caps included, against central
// differences along random directions of a randomly deformed curved ventricle.
TEST(MixedCavity, VolumeGradientMatchesFiniteDifferences) {
  MixedSolid solid("lv", Ventricle(0.006, 2), CavityParams());
  const QuadraticEnclosedVolume& volume = solid.cavity_volume(0);
  const Points& rest = solid.quadratic_mesh().rest;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-1e-3, 1e-3);
  Points x = rest;
  for (Index i = 0; i < x.size(); ++i) x.data()[i] += jitter(rng);
  Points g;
  volume.Compute(x, &g);
  for (int trial = 0; trial < 3; ++trial) {
    Points d(3, x.cols());
    for (Index i = 0; i < d.size(); ++i) d.data()[i] = jitter(rng);
    const double h = 1e-3;
    const double fd = (volume.Compute(x + h * d) - volume.Compute(x - h * d)) / (2 * h);
    const double exact = (g.array() * d.array()).sum();
    // V is a cubic in x: central differences err by h² V'''/6, far below 1e-9 of the
    // derivative's bound ‖∂V/∂x‖ ‖d‖ (the derivative itself may cancel to a tenth of that).
    fmt::print("[ info     ] dV/dx · d = {:.6e}, differences {:.6e}, bound {:.3e}\n", exact, fd,
               g.norm() * d.norm());
    EXPECT_NEAR(fd, exact, 1e-9 * g.norm() * d.norm()) << "trial " << trial;
  }
}

/// A blood law for tests: after step k (t + dt = k), V_b(p) = V_k + C (p_k − p).
class ListedLaw final : public CavityLaw {
 public:
  ListedLaw(std::vector<double> p, std::vector<double> v, double compliance)
      : p_(std::move(p)), v_(std::move(v)), c_(compliance) {}
  bool EndVolume(double t, double dt, double p, double& volume) override {
    const auto k = static_cast<std::size_t>(std::lround(t + dt)) - 1;
    if (k >= v_.size()) return false;
    volume = v_[k] + c_ * (p_[k] - p);
    return true;
  }

 private:
  std::vector<double> p_, v_;
  double c_;
};

// A ventricle inflated by a prescribed cavity pressure p_k over four steps gives volumes V_k.
// The same ventricle coupled to a blood law V_b(p) = V_k + C (p_k − p) (C that of blood with a
// 20 MPa bulk modulus) must find p = p_k: the pressure solved with the wall is the pressure
// that, prescribed, encloses the blood. Incompressible: the wall keeps its volume.
TEST(MixedCavity, CoupledPressureIsThePressureThatEnclosesTheBloodsVolume) {
  auto mesh = Ventricle(0.012);
  MixedSolid prescribed("lv", mesh, CavityParams());
  HoldBase(prescribed);
  std::vector<double> p, v;
  for (int k = 1; k <= 4; ++k) {
    p.push_back(400.0 * k);
    prescribed.WriteField(prescribed.FindField("lumen_pressure"),
                          Eigen::MatrixXd::Constant(1, 1, p.back()));
    const StepStatus status = prescribed.Step(1);
    ASSERT_TRUE(status.ok()) << status.what << ": " << prescribed.failure_detail();
    v.push_back(prescribed.CavityVolume(0));
  }
  const double rest_cavity = MixedSolid("rest", mesh, CavityParams()).CavityVolume(0);
  EXPECT_GT(v.back(), 1.15 * rest_cavity);  // a large inflation

  MixedSolid coupled("lv", mesh, CavityParams());
  HoldBase(coupled);
  const double rest_wall = coupled.CurrentVolume();
  ListedLaw law(p, v, v.front() / 20e6);
  coupled.AttachCavityLaw("lumen", &law);
  EXPECT_THROW(coupled.AttachCavityLaw("lumen", &law), InputError);
  EXPECT_THROW(coupled.AttachCavityLaw("atrium", &law), InputError);
  for (std::size_t k = 0; k < 4; ++k) {
    const StepStatus status = coupled.Step(1);
    ASSERT_TRUE(status.ok()) << status.what << ": " << coupled.failure_detail();
    EXPECT_NEAR(coupled.CavityPressure(0), p[k], 1e-7 * p[k]) << "step " << k + 1;
    EXPECT_NEAR(coupled.CavityVolume(0), v[k], 1e-10 * v[k]);
    EXPECT_LE(coupled.last_newton().iterations, 12);
    EXPECT_NEAR(coupled.CurrentVolume(), rest_wall, 1e-4 * rest_wall);
  }
  EXPECT_EQ(ReadGlobal(coupled, "lumen_pressure"), coupled.CavityPressure(0));
  // A coupled cavity's pressure is the solve's, not the writer's.
  coupled.WriteField(coupled.FindField("lumen_pressure"), Eigen::MatrixXd::Constant(1, 1, 7.0));
  EXPECT_NE(coupled.CavityPressure(0), 7.0);
}

// The follower tangent of a coupled cavity's pressure, −p ∂²V/∂u², with the element terms,
// against central differences of the residual (directions that leave the held rim alone: the
// caps' share, left out of the tangent, moves only with the rim).
TEST(MixedCavity, TangentWithTheCavityPressureMatchesFiniteDifferences) {
  auto mesh = Ventricle(0.012, 2);
  const double rest_cavity = MixedSolid("rest", mesh, CavityParams()).CavityVolume(0);
  MixedSolid loaded("lv", mesh, CavityParams());
  HoldBase(loaded);
  ListedLaw law({0}, {1.1 * rest_cavity}, 1e-12);  // inflate the cavity by a tenth
  loaded.AttachCavityLaw("lumen", &law);
  const StepStatus status = loaded.Step(1);
  ASSERT_TRUE(status.ok()) << status.what << ": " << loaded.failure_detail();
  ASSERT_GT(loaded.CavityPressure(0), 100);
  // A state away from the solution and directions that leave the rim alone.
  const Points& rest = loaded.quadratic_mesh().rest;
  VecX z = VecX::Zero(loaded.num_unknowns());
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> jitter(-1e-4, 1e-4);
  VecX d = VecX::Zero(z.size());
  for (Index a = 0; a < rest.cols(); ++a) {
    const Vec3 x = rest.col(a);
    if (x.z() > 0.012 - 1e-9) continue;  // the rim and the base
    z.segment<3>(3 * a) = 0.05 * Vec3(x.x(), x.y(), 0);
    d.segment<3>(3 * a) = Vec3(jitter(rng), jitter(rng), jitter(rng));
  }
  for (Index i = 3 * rest.cols(); i < z.size(); ++i) d[i] = jitter(rng);
  VecX r0, rp, rm;
  SparseMatrix jacobian;
  ASSERT_TRUE(loaded.EvaluateUnconstrained(z, 1.0, r0, &jacobian));
  const double h = 1e-3;
  ASSERT_TRUE(loaded.EvaluateUnconstrained(z + h * d, 1.0, rp, nullptr));
  ASSERT_TRUE(loaded.EvaluateUnconstrained(z - h * d, 1.0, rm, nullptr));
  const VecX fd = (rp - rm) / (2 * h);
  const VecX jd = jacobian * d;
  EXPECT_LT((fd - jd).norm(), 1e-6 * jd.norm());
  // The cavity's share is there: the same without the pressure differs.
  VecX r_free;
  SparseMatrix j_free;
  MixedSolid unloaded("lv", mesh, CavityParams());
  ASSERT_TRUE(unloaded.EvaluateUnconstrained(z, 1.0, r_free, &j_free));
  EXPECT_GT((j_free * d - jd).norm(), 1e-4 * jd.norm());
}

}  // namespace
}  // namespace gipsi
