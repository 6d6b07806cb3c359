// GridMonodomain (finite differences on a Cartesian grid): the exact Nagumo front, agreement
// with the P1 tet object on a slab as both are refined, conservation, interpolation for other
// objects, and input errors.

#include "gipsi/models/ep/grid_monodomain.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "models/ep/ep_tissue_test_util.h"

namespace gipsi {
namespace {

using testing::DiffusionParams;
using ::testing::HasSubstr;
using testing::NagumoCell;
using testing::RunUntil;

// Front position [mm] on the grid's edge y = z = 0 where u = 1/2 (nodes 0..n_x of that edge).
double GridFront(const GridMonodomain& tissue) {
  const auto u = tissue.voltage();
  const CartesianGrid& g = tissue.grid();
  const double h = 1e3 * g.spacing().x();
  for (int i = 1; i <= g.cells[0]; ++i) {
    const double u0 = u[g.node(i - 1, 0, 0)], u1 = u[g.node(i, 0, 0)];
    if (u0 >= 0.5 && u1 < 0.5) return h * (i - 1 + (u0 - 0.5) / (u0 - u1));
  }
  return NAN;
}

// As the tet test: speed of the exact Nagumo front (c = 0.35355 mm/ms for D = 1 mm²/ms,
// k = 1 /ms, a = 0.25) on a 32 mm bar, from the positions at 16 and 32 ms.
double GridNagumoSpeed(double dx, double dt) {
  CartesianGrid grid{
      Vec3::Zero(), 1e-3 * Vec3(32, dx, dx), {static_cast<int>(std::lround(32 / dx)), 1, 1}};
  EpTissueParams params = DiffusionParams(NagumoCell(1.0, 0.25), 1.0, 1.0);
  params.linear.tolerance = 1e-10;
  GridMonodomain tissue("bar", grid, params);
  Eigen::MatrixXd u(1, grid.num_nodes());
  for (Index i = 0; i < grid.num_nodes(); ++i)
    u(0, i) = 1 / (1 + std::exp((1e3 * tissue.domain().nodes(0, i) - 4.0) / std::sqrt(2.0)));
  tissue.WriteField(tissue.FindField("V"), u);
  EXPECT_TRUE(RunUntil(tissue, 1e-3 * dt, 16e-3).ok());
  const double x16 = GridFront(tissue);
  EXPECT_TRUE(RunUntil(tissue, 1e-3 * dt, 16e-3).ok());
  return (GridFront(tissue) - x16) / 16;
}

// The 7-point stencil with a diagonal mass is second order in dx, the splitting first order in
// dt, so with dt ∝ dx² the speed error falls 4× per halving (thresholds as in the tet test:
// order above 1.8 and the finest error under 0.05 %).
TEST(GridMonodomainTest, NagumoFrontSpeedConvergesAtSecondOrder) {
  const double exact = std::sqrt(0.5) * 0.5;
  std::vector<double> errors;
  for (double dx : {0.5, 0.25, 0.125}) {
    const double c = GridNagumoSpeed(dx, 0.08 * dx * dx);
    errors.push_back(std::abs(c - exact) / exact);
    std::printf("grid dx %.3f mm: c = %.5f mm/ms (exact %.5f), relative error %.3e\n", dx, c, exact,
                errors.back());
  }
  for (std::size_t i = 1; i < errors.size(); ++i) {
    std::printf("observed order %.2f\n", std::log2(errors[i - 1] / errors[i]));
    EXPECT_GT(std::log2(errors[i - 1] / errors[i]), 1.8);
  }
  EXPECT_LT(errors.back(), 5e-4);
}

// The FD grid and the P1 tets share the node lattice of a box, so their activation maps can be
// compared node by node. A quasi-2-D slab 8 × 4 mm, one cell thick, Nagumo (k = 1 /ms, a = 0.05)
// with D_l = 1 and D_t = 0.25 mm²/ms (fibres along x), stimulated in a 2 mm corner square for
// 2 ms (well above the critical nucleus, so no near-threshold delay amplifies small
// differences). Both are second-order discretisations of the same equation, so the largest
// difference of activation times must shrink as the lattice is refined (~4× per halving
// expected; asserted ≥ 2.5×, and below 1 % of the latest activation time at the finest).
TEST(GridMonodomainTest, AgreesWithTetsOnTheSlabAsBothAreRefined) {
  std::vector<double> differences;
  for (double dx : {0.5, 0.25, 0.125}) {
    const Vec3 size(8, 4, dx);  // mm
    const std::array<int, 3> cells = {static_cast<int>(std::lround(8 / dx)),
                                      static_cast<int>(std::lround(4 / dx)), 1};
    EpTissueParams params = DiffusionParams(NagumoCell(1.0, 0.05), 1.0, 0.25);
    params.activation_threshold = 0.5;
    params.stimuli.push_back({"corner",
                              BoxRegion{Vec3::Constant(-1), Vec3(2.0001e-3, 2.0001e-3, 1)}, 1.0,
                              PulseTrain{0.0, 2.0}});
    GridMonodomain grid("grid", CartesianGrid{Vec3::Zero(), 1e-3 * size, cells}, params);
    Monodomain tets("tets", std::make_shared<Mesh>(MakeTetBox(Vec3::Zero(), 1e-3 * size, cells)),
                    params);
    const double dt = 0.01;  // ms
    ASSERT_TRUE(RunUntil(grid, 1e-3 * dt, 16e-3).ok());
    ASSERT_TRUE(RunUntil(tets, 1e-3 * dt, 16e-3).ok());
    ASSERT_GT(grid.activation_time().minCoeff(), -1) << "the grid did not activate everywhere";
    ASSERT_GT(tets.activation_time().minCoeff(), -1) << "the tets did not activate everywhere";
    const double difference =
        (grid.activation_time() - tets.activation_time()).cwiseAbs().maxCoeff();
    std::printf(
        "dx %.3f mm: latest activation %.3f ms (grid) %.3f ms (tets), max |difference| "
        "%.4f ms\n",
        dx, grid.activation_time().maxCoeff(), tets.activation_time().maxCoeff(), difference);
    differences.push_back(difference);
    if (dx == 0.125) {
      EXPECT_LT(difference, 0.01 * tets.activation_time().maxCoeff());
    }
  }
  EXPECT_GT(differences[0] / differences[1], 2.5);
  EXPECT_GT(differences[1] / differences[2], 2.5);
}

// K's rows sum to zero and M is diagonal: diffusion conserves Σ m_i V_i (as on tets).
TEST(GridMonodomainTest, DiffusionConservesTheVoltageIntegral) {
  EpTissueParams params = DiffusionParams(NagumoCell(1.0, 0.25), 0.5, 0.1);
  params.stimuli.clear();
  params.linear.tolerance = 1e-13;
  GridMonodomain tissue("block", CartesianGrid{Vec3::Zero(), Vec3(0.003, 0.002, 0.001), {6, 4, 2}},
                        params);
  // Nagumo's reaction vanishes at u = 0 and u = 1: a field of 0s and 1s only diffuses at first;
  // the integral is checked after one step, before the reaction acts on intermediate values.
  Eigen::MatrixXd v(1, tissue.num_nodes());
  for (Index i = 0; i < tissue.num_nodes(); ++i) v(0, i) = (i % 3 == 0) ? 1.0 : 0.0;
  tissue.WriteField(tissue.FindField("V"), v);
  const double before = tissue.VoltageIntegral();
  ASSERT_TRUE(tissue.Step(1e-5).ok());
  EXPECT_GT((tissue.voltage().transpose() - v).cwiseAbs().maxCoeff(), 0.01);
  EXPECT_NEAR(tissue.VoltageIntegral() / before, 1.0, 1e-12);
}

// Interpolation for probes and volume connectors: exact for linear fields (linear on each Kuhn
// simplex), the node values at the nodes, and clamped with the distance reported outside.
TEST(GridMonodomainTest, MapFromNodesIsExactForLinearFields) {
  EpTissueParams params = DiffusionParams(NagumoCell(1.0, 0.25), 0.1, 0.1);
  GridMonodomain tissue("g", CartesianGrid{Vec3(0.001, 0, 0), Vec3(0.005, 0.002, 0.003), {4, 3, 5}},
                        params);
  const Points& nodes = tissue.domain().nodes;
  Eigen::MatrixXd f(1, nodes.cols());
  for (Index i = 0; i < nodes.cols(); ++i)
    f(0, i) = 3 + 100 * nodes(0, i) - 200 * nodes(1, i) + 50 * nodes(2, i);
  Points targets(3, 5);
  targets << 0.0012, 0.0049, 0.003, 0.001, 0.0031,  //
      0.0001, 0.0019, 0.001, 0.0, 0.0013,           //
      0.0029, 0.0002, 0.0015, 0.0, 0.0007;
  const PointMap map = tissue.MapFromNodes(targets);
  Eigen::MatrixXd out(1, targets.cols());
  map.Apply(f, out);
  for (Index t = 0; t < targets.cols(); ++t)
    EXPECT_NEAR(out(0, t), 3 + 100 * targets(0, t) - 200 * targets(1, t) + 50 * targets(2, t),
                1e-14);
  EXPECT_LT(map.max_distance(), 1e-15);
  const PointMap outside = tissue.MapFromNodes(Points(Vec3(0.0, 0.001, 0.001)));
  EXPECT_NEAR(outside.max_distance(), 0.001, 1e-15);
}

TEST(GridMonodomainTest, BadInputGetsAClearError) {
  EpTissueParams params = DiffusionParams(NagumoCell(1.0, 0.25), 0.4, 0.1);
  const CartesianGrid grid{Vec3::Zero(), Vec3::Constant(0.001), {2, 2, 2}};
  params.fibre = Vec3(1, 1, 0);
  try {
    GridMonodomain tissue("g", grid, params);
    FAIL() << "rotated fibres were accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("not along a grid axis"));
  }
  params.fibre = Vec3::UnitZ();
  params.lumped_mass = false;
  try {
    GridMonodomain tissue("g", grid, params);
    FAIL() << "consistent mass was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("lumped"));
  }
}

}  // namespace
}  // namespace gipsi
