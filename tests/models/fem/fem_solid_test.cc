#include "gipsi/models/fem/fem_solid.h"

#include <omp.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "models/fem/fem_test_util.h"

namespace gipsi {
namespace {

using testing::AccurateParams;
using testing::AllLaws;
using testing::DistortedBox;
using ::testing::HasSubstr;
using testing::Law;
using testing::VerticesWhere;

TEST(FemSolid, PassesThePatchTestForEveryLaw) {
  // A homogeneous deformation x = X + A X + b imposed on the boundary of a distorted mesh is
  // an exact solution of the discrete equations for P1 elements (constant F, constant P, and
  // Σ_e V P ∇N_a = 0 at interior nodes), for linear and nonlinear laws alike.
  Mat3 A;
  A << 1.0, 0.4, -0.3, 0.2, -0.5, 0.1, 0.3, 0.6, 0.8;
  A *= 1e-3;  // small strain
  const Vec3 b(1e-4, -2e-4, 3e-4);
  for (const std::string& law : AllLaws()) {
    SCOPED_TRACE(law);
    auto mesh = DistortedBox(3);
    FemSolid fem("patch", mesh, AccurateParams(law, ImplicitSchemeKind::kStatic));
    for (Index j = 0; j < fem.boundary().num_vertices(); ++j) {
      const Vec3 X = mesh->nodes.col(fem.boundary().vertex_to_node[static_cast<std::size_t>(j)]);
      fem.boundary_conditions().PrescribeDisplacement(j, A * X + b);
    }
    ASSERT_TRUE(fem.Step(1.0).ok()) << fem.failure_detail();
    double worst = 0;
    for (Index i = 0; i < mesh->num_nodes(); ++i) {
      const Vec3 X = mesh->nodes.col(i);
      worst = std::max(worst, (fem.x().segment<3>(3 * i) - (X + A * X + b)).norm());
    }
    // Newton stops at a residual 1e-12 of the initial one: the displacement error is of that
    // order relative to the 1e-3 displacements, i.e. round-off.
    EXPECT_LT(worst, 1e-12);
    // Stresses are constant (to round-off relative to their size).
    const Mat3 s0 = fem.CauchyStress(0);
    for (Index e = 1; e < fem.num_elements(); ++e)
      ASSERT_LT((fem.CauchyStress(e) - s0).norm(), 1e-8 * s0.norm() + 1e-12) << "element " << e;
  }
}

TEST(FemSolid, TangentMatchesFiniteDifferencesOfInternalForcesForEveryLaw) {
  for (const std::string& law : AllLaws()) {
    SCOPED_TRACE(law);
    auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3::Ones(), {2, 1, 1}));
    FemSolid fem("tangent", mesh, AccurateParams(law, ImplicitSchemeKind::kStatic));
    // A finite deformation: stretch, shear and a random perturbation (det F stays positive).
    Mat3 F;
    F << 1.2, 0.15, 0.0, -0.1, 0.9, 0.2, 0.05, 0.0, 1.1;
    VecX x(3 * mesh->num_nodes());
    srand(3);
    for (Index i = 0; i < mesh->num_nodes(); ++i)
      x.segment<3>(3 * i) = F * mesh->nodes.col(i) + 0.03 * Vec3::Random();
    SparseMatrix K;
    ASSERT_TRUE(fem.CalcStiffness(x, K));
    const Eigen::MatrixXd dense = Eigen::MatrixXd(K);
    VecX fp(x.size()), fm(x.size());
    // Central differences: truncation ~h² |f'''| and round-off ~1e-16 |f| / h; with h = 1e-6 m
    // on a unit mesh both are ~1e-8 of the stiffness scale (E ~ 1e4 Pa · 1 m).
    const double h = 1e-6;
    double worst = 0;
    for (Index j = 0; j < x.size(); ++j) {
      VecX xp = x, xm = x;
      xp[j] += h;
      xm[j] -= h;
      ASSERT_TRUE(fem.CalcInternalForces(xp, fp));
      ASSERT_TRUE(fem.CalcInternalForces(xm, fm));
      worst = std::max(worst, ((fp - fm) / (2 * h) - dense.col(j)).cwiseAbs().maxCoeff());
    }
    EXPECT_LT(worst, 1e-5 * dense.cwiseAbs().maxCoeff());
    EXPECT_LT((dense - dense.transpose()).cwiseAbs().maxCoeff(),
              1e-9 * dense.cwiseAbs().maxCoeff());
  }
}

TEST(FemSolid, RigidRotationIsStressFreeExceptForTheLinearLaw) {
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  for (const std::string& law : AllLaws()) {
    SCOPED_TRACE(law);
    auto mesh = DistortedBox(2);
    FemSolid fem("rotation", mesh, AccurateParams(law, ImplicitSchemeKind::kStatic));
    VecX x(3 * mesh->num_nodes()), f(3 * mesh->num_nodes());
    for (Index i = 0; i < mesh->num_nodes(); ++i)
      x.segment<3>(3 * i) = R * mesh->nodes.col(i) + Vec3(0.3, -0.2, 1.0);
    ASSERT_TRUE(fem.CalcInternalForces(x, f));
    // Force scale: E · (element size)² ≈ 1e4 · 0.25 = 2.5e3 N; a 0.7 rad rotation seen by the
    // linear law as strain ~0.3 gives forces of that order.
    if (law.find("\"Linear\"") != std::string::npos)
      EXPECT_GT(f.cwiseAbs().maxCoeff(), 10.0);
    else
      EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-9);
  }
}

}  // namespace
}  // namespace gipsi

namespace gipsi {
namespace {

using testing::FacesWhere;

/// Tip deflection of a clamped cantilever [0, L]×[0, h]×[0, h] with `cells` along x (h/L·cells
/// across), under a tip traction (total force P along −z) or its own weight.
double CantileverTip(int cells, bool gravity) {
  const double L = 10, h = 1;
  auto mesh = std::make_shared<const Mesh>(
      MakeTetBox(Vec3::Zero(), Vec3(L, h, h), {10 * cells, cells, cells}));  // cubic cells
  FemParams p = AccurateParams(R"({"law": "Linear", "youngs_modulus": 1e8, "poisson_ratio": 0.3})",
                               ImplicitSchemeKind::kStatic);
  if (gravity) p.gravity = Vec3(0, 0, -1.0);  // q = ρ g A = 1000 N/m
  FemSolid fem("beam", mesh, p);
  for (Index j : VerticesWhere(fem, [](const Vec3& X) { return X.x() == 0; }))
    fem.boundary_conditions().Fix(j);
  if (!gravity)
    for (Index f : FacesWhere(fem, [&](const Vec3& X) { return X.x() == L; }))
      fem.boundary_conditions().SetTraction(f, Vec3(0, 0, -100.0));  // P = 100 N on h² = 1 m²
  EXPECT_TRUE(fem.Step(1.0).ok()) << fem.failure_detail();
  // Mean vertical displacement of the tip face.
  double sum = 0;
  int count = 0;
  for (Index i = 0; i < mesh->num_nodes(); ++i)
    if (mesh->nodes(0, i) == L) {
      sum += fem.x()[3 * i + 2] - mesh->nodes(2, i);
      ++count;
    }
  return -sum / count;
}

TEST(FemSolid, CantileverDeflectionConvergesToBeamTheory) {
  // Beam theory, E = 1e8 Pa, ν = 0.3, L = 10 m, square h = 1 m (I = 1/12 m⁴, A = 1 m²):
  // tip load P = 100 N: Euler–Bernoulli PL³/(3EI) = 4.0e-3 m plus Timoshenko shear
  // PL/(κGA) with κ = 5/6, G = E/2.6 → 3.12e-5 m; uniform load q = 1000 N/m: qL⁴/(8EI) = 0.15 m
  // plus shear qL²/(2κGA) = 1.56e-3 m.
  const double E = 1e8, I = 1.0 / 12, L = 10, G = E / 2.6, kappa = 5.0 / 6.0;
  const double tip_exact = 100 * L * L * L / (3 * E * I) + 100 * L / (kappa * G);
  const double grav_exact = 1000 * std::pow(L, 4) / (8 * E * I) + 1000 * L * L / (2 * kappa * G);
  for (bool gravity : {false, true}) {
    SCOPED_TRACE(gravity ? "gravity" : "tip load");
    const double exact = gravity ? grav_exact : tip_exact;
    double d[3];
    for (int k = 0; k < 3; ++k) d[k] = CantileverTip(2 << k, gravity);
    // Linear tets lock in bending: coarse meshes are too stiff, the deflection grows
    // monotonically, and the error against beam theory falls faster than first order with a
    // rate that rises towards the asymptotic second order (measured: 50 %, 21 %, 7.0 % for
    // 2, 4, 8 cubic cells through the thickness, orders 1.2 then 1.6).
    double error[3];
    for (int k = 0; k < 3; ++k) error[k] = (exact - d[k]) / exact;
    EXPECT_GT(error[0], error[1]);
    EXPECT_GT(error[1], error[2]);
    EXPECT_GT(error[2], -0.02);  // never more flexible than the continuum beyond its 3-D effects
    const double order01 = std::log2(error[0] / error[1]);
    const double order12 = std::log2(error[1] / error[2]);
    std::printf(
        "cantilever (%s): tip %.5g %.5g %.5g m, exact %.5g m, errors %.1f %.1f %.1f %%, "
        "observed orders %.2f %.2f\n",
        gravity ? "gravity" : "tip load", d[0], d[1], d[2], exact, 100 * error[0], 100 * error[1],
        100 * error[2], order01, order12);
    EXPECT_GT(order01, 1.0);
    EXPECT_GT(order12, order01);
    EXPECT_LT(error[2], 0.10);
  }
}

TEST(FemSolid, UniaxialStretchOfANeoHookeanCubeMatchesTheClosedForm) {
  // Symmetry planes x=0, y=0, z=0 and a prescribed stretch λ on x=1: a homogeneous uniaxial
  // stress state F = diag(λ, λt, λt) with P22 = 0, which P1 elements reproduce exactly.
  const double E = 1e4, nu = 0.3, stretch = 1.3;
  const double mu = E / (2 * (1 + nu)), lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  auto P = [&](double s, double t, bool lateral) {  // P11 (or P22) of the Bonet–Wood law
    const double lnj = std::log(s * t * t);
    return lateral ? mu * (t - 1 / t) + lambda * lnj / t : mu * (s - 1 / s) + lambda * lnj / s;
  };
  double lo = 0.5, hi = 1.0;  // P22(λt) is increasing; bisect for P22 = 0
  for (int i = 0; i < 200; ++i) (P(stretch, 0.5 * (lo + hi), true) > 0 ? hi : lo) = 0.5 * (lo + hi);
  const double lateral = 0.5 * (lo + hi);
  const double p11 = P(stretch, lateral, false);

  auto mesh = std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3::Ones(), {2, 2, 2}));
  FemParams params =
      AccurateParams(R"({"law": "NeoHookean", "youngs_modulus": 1e4, "poisson_ratio": 0.3})",
                     ImplicitSchemeKind::kStatic);
  params.load_steps = 4;
  FemSolid fem("cube", mesh, params);
  auto& bcs = fem.boundary_conditions();
  for (int axis = 0; axis < 3; ++axis)
    for (Index j : VerticesWhere(fem, [&](const Vec3& X) { return X[axis] == 0; }))
      bcs.Fix(j, static_cast<AxisMask>(1 << axis));
  const auto right = VerticesWhere(fem, [](const Vec3& X) { return X.x() == 1; });
  for (Index j : right) bcs.PrescribeDisplacement(j, Vec3(stretch - 1, 0, 0), 1);
  ASSERT_TRUE(fem.Step(1.0).ok()) << fem.failure_detail();

  Eigen::MatrixXd reaction(3, fem.boundary().num_vertices());
  fem.ReadField(fem.FindField("reaction_force"), reaction);
  double total = 0;
  for (Index j : right) total += reaction(0, j);
  EXPECT_NEAR(total, p11, 1e-8 * p11);               // force on the unit reference area = P11
  const Index corner = 3 * (mesh->num_nodes() - 1);  // node (1, 1, 1)
  EXPECT_NEAR(fem.x()[corner + 1], lateral, 1e-10);
  EXPECT_NEAR(fem.x()[corner + 2], lateral, 1e-10);
}

TEST(FemSolid, FollowerPressureInflatesACylinderAsLame) {
  // Plane strain thick cylinder, inner radius a = 1, outer b = 2, internal pressure p:
  // u(r) = (1+ν) p a² / (E (b² − a²)) · ((1 − 2ν) r + b² / r).
  const double a = 1, b = 2, E = 1e6, nu = 0.3, p = 1e3;
  auto u_exact = [&](double r) {
    return (1 + nu) * p * a * a / (E * (b * b - a * a)) * ((1 - 2 * nu) * r + b * b / r);
  };
  double errors[2];
  for (int level = 0; level < 2; ++level) {
    const double size = level == 0 ? 0.3 : 0.15;
    auto mesh = std::make_shared<const Mesh>(MakeCylinderShell(a, b, 0.3, size));
    FemParams params =
        AccurateParams(R"({"law": "Linear", "youngs_modulus": 1e6, "poisson_ratio": 0.3})",
                       ImplicitSchemeKind::kStatic);
    FemSolid fem("cylinder", mesh, params);
    auto& bcs = fem.boundary_conditions();
    for (Index j : VerticesWhere(fem, [](const Vec3& X) {
           return std::abs(X.z()) < 1e-9 || std::abs(X.z() - 0.3) < 1e-9;
         }))
      bcs.Fix(j, 4);  // plane strain
    for (Index f : FacesWhere(fem, [&](const Vec3& X) { return X.head<2>().norm() < a + 1e-6; }))
      bcs.SetPressure(f, p);
    // Remove the rigid in-plane modes by holding three outer vertices to the exact solution
    // (the exact field is radial, so these constraints carry no load).
    const Vec3 targets[3] = {Vec3(b, 0, 0), Vec3(0, b, 0), Vec3(-b, 0, 0)};
    const AxisMask masks[3] = {2, 1, 2};
    for (int k = 0; k < 3; ++k) {
      Index best = 0;
      double dist = 1e30;
      for (Index j = 0; j < fem.boundary().num_vertices(); ++j) {
        const Vec3 X = mesh->nodes.col(fem.boundary().vertex_to_node[static_cast<std::size_t>(j)]);
        const double d = (X - Vec3(targets[k].x(), targets[k].y(), X.z())).norm();
        if (d < dist) dist = d, best = j;
      }
      const Vec3 X = mesh->nodes.col(fem.boundary().vertex_to_node[static_cast<std::size_t>(best)]);
      const double r = X.head<2>().norm();
      bcs.PrescribeDisplacement(best, u_exact(r) / r * Vec3(X.x(), X.y(), 0), masks[k]);
    }
    ASSERT_TRUE(fem.Step(1.0).ok()) << fem.failure_detail();
    double worst = 0;
    for (Index i = 0; i < mesh->num_nodes(); ++i) {
      const Vec3 X = mesh->nodes.col(i);
      const double r = X.head<2>().norm();
      const Vec3 u = fem.x().segment<3>(3 * i) - X;
      worst = std::max(worst, std::abs(u.head<2>().dot(X.head<2>()) / r - u_exact(r)));
    }
    errors[level] = worst / u_exact(a);
    std::printf("Lame cylinder, mesh size %.2f: %ld tets, max radial error %.3g %%\n", size,
                static_cast<long>(fem.num_elements()), 100 * errors[level]);
  }
  // P1 tets with a faceted inner surface: several per cent at size 0.3, shrinking with h at
  // about second order (the faceting of the curved boundary is itself an O(h²) error).
  // Measured: 7.5 % at size 0.3 and 2.3 % at 0.15 (observed order 1.7).
  EXPECT_LT(errors[0], 0.10);
  EXPECT_LT(errors[1], 0.4 * errors[0]);
}

}  // namespace
}  // namespace gipsi

namespace gipsi {
namespace {

TEST(FemSolid, AssemblyGivesTheSameBitsForAnyThreadCount) {
  // Element chunks of one colour share no node and each entry sums its contributions colour by
  // colour, chunk by chunk, so the result cannot depend on how a colour is split among threads.
  auto mesh = std::make_shared<const Mesh>(
      MakeTetBox(Vec3::Zero(), Vec3::Ones(), {20, 20, 20}));  // 48,000 tets: parallel loops
  FemSolid fem(
      "block", mesh,
      AccurateParams(R"({"law": "NeoHookean", "youngs_modulus": 1e4, "poisson_ratio": 0.3})",
                     ImplicitSchemeKind::kStatic));
  VecX x(3 * mesh->num_nodes());
  for (Index i = 0; i < mesh->num_nodes(); ++i) {
    const Vec3 X = mesh->nodes.col(i);
    x.segment<3>(3 * i) = X + 0.05 * Vec3(std::sin(3 * X.y()), X.x() * X.z(), std::cos(2 * X.x()));
  }
  auto run = [&](int threads, VecX& f, SparseMatrix& K) {
    const int saved = omp_get_max_threads();
    omp_set_num_threads(threads);
    EXPECT_TRUE(fem.CalcInternalForces(x, f));
    EXPECT_TRUE(fem.CalcStiffness(x, K));
    omp_set_num_threads(saved);
  };
  VecX f1(x.size()), f2(x.size());
  SparseMatrix k1, k2;
  run(1, f1, k1);
  run(2, f2, k2);
  ASSERT_EQ(k1.nonZeros(), k2.nonZeros());
  EXPECT_EQ(
      0, std::memcmp(f1.data(), f2.data(), sizeof(double) * static_cast<std::size_t>(f1.size())));
  EXPECT_EQ(0, std::memcmp(k1.valuePtr(), k2.valuePtr(),
                           sizeof(double) * static_cast<std::size_t>(k1.nonZeros())));
}

TEST(FemSolid, LumpedAndConsistentMassCarryTheSameTotalMassAndWeight) {
  auto mesh = DistortedBox(3);
  for (bool lumped : {false, true}) {
    FemParams p =
        AccurateParams(R"({"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3})",
                       ImplicitSchemeKind::kBackwardEuler);
    p.lumped_mass = lumped;
    p.density = 1200;
    FemSolid fem("free", mesh, p);
    // A uniform velocity is a rigid motion: kinetic energy ½ m v² with m = ρ V = 1200 kg.
    Points v = Points::Zero(3, mesh->num_nodes());
    v.row(0).setConstant(2.0);
    fem.WriteField(fem.FindField("velocity"), v);
    EXPECT_NEAR(fem.KineticEnergy(), 0.5 * 1200 * 4.0, 1e-9);
  }
}

}  // namespace
}  // namespace gipsi

namespace gipsi {
namespace {

TEST(FemSolid, CavityPressureInflatesItsVolumeAsLame) {
  // The lumen of a plane-strain thick cylinder (a = 1, b = 2, height 0.3): its capped volume
  // starts at the faceted π a² h, and a lumen pressure p widens it by 2π a u(a) h to first order,
  // with the Lamé u(a).
  const double a = 1, b = 2, h = 0.3, E = 1e6, nu = 0.3, p = 1e3;
  auto mesh = std::make_shared<const Mesh>(MakeCylinderShell(a, b, h, 0.15));
  FemParams params =
      AccurateParams(R"({"law": "Linear", "youngs_modulus": 1e6, "poisson_ratio": 0.3})",
                     ImplicitSchemeKind::kStatic);
  params.cavities.push_back(CavitySpec{"lumen", GroupRegion{"inner"}});
  FemSolid fem("cylinder", mesh, params);
  auto& bcs = fem.boundary_conditions();
  for (Index j : VerticesWhere(fem, [&](const Vec3& X) {
         return std::abs(X.z()) < 1e-9 || std::abs(X.z() - h) < 1e-9;
       }))
    bcs.Fix(j, 4);
  // Rigid in-plane modes: hold y of the outer vertices nearest (±b, 0) and x of the one nearest
  // (0, b). The exact field is radial, so these hold (nearly) no load, and any mismatch is a
  // rigid translation, which leaves the volume alone.
  const std::pair<Vec3, AxisMask> holds[3] = {
      {Vec3(b, 0, 0), 2}, {Vec3(-b, 0, 0), 2}, {Vec3(0, b, 0), 1}};
  for (const auto& [target, mask] : holds) {
    Index best = 0;
    double dist = 1e30;
    for (Index j = 0; j < fem.boundary().num_vertices(); ++j) {
      const Vec3 X = mesh->nodes.col(fem.boundary().vertex_to_node[static_cast<std::size_t>(j)]);
      const double d = (X.head<2>() - target.head<2>()).norm();
      if (d < dist) dist = d, best = j;
    }
    bcs.Fix(best, mask);
  }
  const FieldId volume = fem.FindField("lumen_volume");
  Eigen::MatrixXd value(1, 1);
  fem.ReadField(volume, value);
  const double v0 = value(0, 0);
  EXPECT_NEAR(v0 / (std::numbers::pi * a * a * h), 1.0, 0.02);  // faceting shrinks it slightly
  value(0, 0) = p;
  fem.WriteField(fem.FindField("lumen_pressure"), value);
  ASSERT_TRUE(fem.Step(1.0).ok()) << fem.failure_detail();
  fem.ReadField(volume, value);
  const double u_a = (1 + nu) * p * a * a / (E * (b * b - a * a)) * ((1 - 2 * nu) * a + b * b / a);
  const double expected = 2 * std::numbers::pi * a * u_a * h;
  std::printf("lumen volume %.6g -> %.6g m^3: change %.4g, Lame %.4g (ratio %.4f)\n", v0,
              value(0, 0), value(0, 0) - v0, expected, (value(0, 0) - v0) / expected);
  // P1 accuracy at this size (the Lamé test measured 2.3 % nodal error): 5 %.
  EXPECT_NEAR((value(0, 0) - v0) / expected, 1.0, 0.05);
}

TEST(FemSolid, InvertedRestTetsAreRefusedByTheirIds) {
  // A generated mesh has no file ids: its tets are listed by 0-based index, and the message says
  // so (it used to end in "(0-based indexs)"). With file ids the file's own are listed.
  Mesh mesh = MakeTetBox(Vec3::Zero(), Vec3::Ones(), {1, 1, 1});
  std::swap(mesh.tets(2, 3), mesh.tets(3, 3));
  FemParams params =
      AccurateParams(R"({"law": "Linear", "youngs_modulus": 1e4, "poisson_ratio": 0.3})",
                     ImplicitSchemeKind::kBackwardEuler);
  auto build = [&](const Mesh& m) {
    try {
      FemSolid fem("cube", std::make_shared<const Mesh>(m), params);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_THAT(build(mesh), HasSubstr("1 tetrahedra are inverted or degenerate (non-positive rest "
                                     "volume), e.g. tets 3 (0-based indices in file order)"));
  for (Index e = 0; e < mesh.num_tets(); ++e) mesh.tet_ids.push_back(101 + e);
  mesh.tet_id_kind = "Gmsh element tag";
  EXPECT_THAT(build(mesh), HasSubstr("e.g. tets 104 (Gmsh element tags)"));
}

}  // namespace
}  // namespace gipsi
