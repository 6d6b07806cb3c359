// MassSpring's active tension: the spring weights that make a nodal tension act like the stress
// T f ⊗ f (mass_spring.h derives them).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "gipsi/geometry/generators.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {
namespace {

constexpr double kLx = 0.04, kLy = 0.03, kLz = 0.02;  // block [m]
constexpr int kNx = 4;                                // node layers 0 … kNx along x

/// A block of 4 × 3 × 2 cells cut into tets (6 or 5 per cell), whose interior nodes are moved
/// randomly in y and z (up to 25 % of a cell) but not in x: every tet still lies between two
/// node planes x = x_i, x_{i+1}, so the tets are irregular but layered.
std::shared_ptr<const Mesh> LayeredBlock(HexSplit split) {
  Mesh mesh = MakeTetBox(Vec3::Zero(), Vec3(kLx, kLy, kLz), {kNx, 3, 2}, split);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.25, 0.25);
  for (Index i = 0; i < mesh.num_nodes(); ++i) {
    Vec3 p = mesh.nodes.col(i);
    const bool inside_y = p.y() > 1e-12 && p.y() < kLy - 1e-12;
    const bool inside_z = p.z() > 1e-12 && p.z() < kLz - 1e-12;
    if (inside_y) p.y() += jitter(rng) * kLy / 3;
    if (inside_z) p.z() += jitter(rng) * kLz / 2;
    mesh.nodes.col(i) = p;
  }
  return std::make_shared<const Mesh>(std::move(mesh));
}

std::unique_ptr<MassSpring> Block(HexSplit split) {
  MassSpringParams params;
  params.gravity.setZero();
  params.fibre = Vec3::UnitX();
  return std::make_unique<MassSpring>("block", LayeredBlock(split), params,
                                      std::make_unique<SymplecticEuler>());
}

class ActiveTension : public ::testing::TestWithParam<HexSplit> {};

TEST_P(ActiveTension, UniformTensionPullsAcrossASectionLikeTheStress) {
  // A uniform tension T along uniform fibres x: the springs crossing any plane between two node
  // layers pull across it with Σ T w_s (d̂_s·x̂) = T × (the block's section), exactly (the
  // derivation in mass_spring.h), so to round-off (1e-12 of the force).
  auto block = Block(GetParam());
  const double tension = 2e4, area = kLy * kLz;
  const Points& rest = block->domain().nodes;
  for (int layer = 0; layer < kNx; ++layer) {
    const double cut = (layer + 0.5) * kLx / kNx;
    double force = 0;
    int crossing = 0;
    for (Index s = 0; s < block->num_springs(); ++s) {
      const Vec3 a = rest.col(block->springs()(0, s)), b = rest.col(block->springs()(1, s));
      if ((a.x() < cut) == (b.x() < cut)) continue;
      ++crossing;
      force += tension * block->active_weights()[s] * std::abs((b - a).normalized().x());
    }
    EXPECT_GT(crossing, 12);
    EXPECT_NEAR(force, tension * area, 1e-12 * tension * area) << "cut at x = " << cut;
  }
  // Springs in a plane x = const carry no fibre tension.
  for (Index s = 0; s < block->num_springs(); ++s) {
    const Vec3 d = rest.col(block->springs()(1, s)) - rest.col(block->springs()(0, s));
    if (std::abs(d.x()) < 1e-12) {
      EXPECT_EQ(block->active_weights()[s], 0.0);
    }
  }
}

TEST_P(ActiveTension, HeldEndFeelsTensionTimesSection) {
  // The same through the object's forces: written as "nodal_active_tension", the contracting
  // block pulls its held x = Lx face inwards, so the reaction there is +T × section along x (the
  // forces at rest are the active ones alone: springs at rest length, no gravity), to 1e-12.
  auto block = Block(GetParam());
  auto& bcs = block->boundary_conditions();
  const auto& v2n = block->boundary().vertex_to_node;
  for (std::size_t j = 0; j < v2n.size(); ++j)
    if (block->domain().nodes(0, v2n[j]) > kLx - 1e-12) bcs.Fix(static_cast<Index>(j), 7);
  const double tension = 2e4;
  block->WriteField(block->FindField("nodal_active_tension"),
                    Eigen::MatrixXd::Constant(1, block->num_nodes(), tension));
  Eigen::MatrixXd reaction(3, block->boundary().num_vertices());
  block->ReadField(block->FindField("reaction_force"), reaction);
  const double expected = tension * kLy * kLz;
  EXPECT_NEAR(reaction.row(0).sum(), expected, 1e-12 * expected);
  // Contractile: a free block shortens along the fibres.
  auto free = Block(GetParam());
  free->WriteField(free->FindField("nodal_active_tension"),
                   Eigen::MatrixXd::Constant(1, free->num_nodes(), tension));
  for (int k = 0; k < 20; ++k) ASSERT_TRUE(free->Step(1e-4).ok());
  const Points& x = free->domain_positions();
  EXPECT_LT(x.row(0).maxCoeff() - x.row(0).minCoeff(), kLx);
}

INSTANTIATE_TEST_SUITE_P(SixAndFiveTetsPerCell, ActiveTension,
                         ::testing::Values(HexSplit::kSix, HexSplit::kFive));

TEST(ActiveTension, FibreWeightFollowsTheFibreField) {
  // Fibres written per tet: along y the same block pulls across y-sections instead, and a
  // spring along x gets no weight from a tet whose fibre is perpendicular to it.
  auto block = Block(HexSplit::kSix);
  const Index ne = block->domain().num_tets();
  Eigen::MatrixXd fibres(3, ne);
  fibres.colwise() = Vec3(0, 2, 0);  // normalised by the object
  block->WriteField(block->FindField("fibre"), fibres);
  const Points& rest = block->domain().nodes;
  for (Index s = 0; s < block->num_springs(); ++s) {
    const Vec3 d = rest.col(block->springs()(1, s)) - rest.col(block->springs()(0, s));
    if (std::abs(d.y()) < 1e-15) {
      EXPECT_EQ(block->active_weights()[s], 0.0);
    }
  }
  Eigen::MatrixXd read(3, ne);
  block->ReadField(block->FindField("fibre"), read);
  EXPECT_NEAR((read.col(0) - Vec3::UnitY()).norm(), 0, 1e-15);
}

}  // namespace
}  // namespace gipsi
