#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/core/kernel.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/models/connectors/boundary_coupling.h"
#include "gipsi/models/connectors/field_copy.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

std::unique_ptr<MassSpring> Block(const std::string& name, const Vec3& lo, const Vec3& hi,
                                  int cells, const MassSpringParams& params = {}) {
  return std::make_unique<MassSpring>(
      name, std::make_shared<const Mesh>(MakeTetBox(lo, hi, {cells, cells, cells})), params,
      std::make_unique<SymplecticEuler>());
}

TEST(FieldCopy, SetOnOneObjectIsReadOnTheOther) {
  auto a = Block("a", Vec3::Zero(), Vec3::Ones(), 2);
  auto b = Block("b", Vec3::Zero(), Vec3::Ones(), 2);
  FieldId va = a->FindField("velocity");
  Eigen::MatrixXd v = Eigen::MatrixXd::Random(3, 27);
  a->WriteField(va, v);
  FieldCopy copy("copy", *a, va, *b, b->FindField("external_force"), FieldCopy::Mapping::kAuto,
                 1.0);
  EXPECT_EQ(copy.mapping(), FieldCopy::Mapping::kDirect);
  ASSERT_TRUE(copy.Fire(0).ok());
  Eigen::MatrixXd got(3, 27);
  b->ReadField(b->FindField("external_force"), got);
  EXPECT_EQ(got, v);
}

TEST(FieldCopy, BarycentricMappingReproducesLinearFieldsAcrossMeshes) {
  // Coarse source, fine target covering the same box: a linear field is interpolated exactly.
  auto coarse = Block("coarse", Vec3::Zero(), Vec3::Ones(), 2);
  auto fine = Block("fine", Vec3::Zero(), Vec3::Ones(), 5);
  Eigen::Matrix3d A;
  A << 1, 2, 3, -1, 0.5, 0, 0.25, 0, -2;
  const Vec3 b(0.1, -0.2, 0.3);
  Eigen::MatrixXd v = (A * coarse->domain().nodes).colwise() + b;
  coarse->WriteField(coarse->FindField("velocity"), v);
  FieldCopy copy("copy", *coarse, coarse->FindField("velocity"), *fine,
                 fine->FindField("external_force"), FieldCopy::Mapping::kAuto, 1.0);
  EXPECT_EQ(copy.mapping(), FieldCopy::Mapping::kBarycentric);
  ASSERT_TRUE(copy.Fire(0).ok());
  Eigen::MatrixXd got(3, fine->num_nodes());
  fine->ReadField(fine->FindField("external_force"), got);
  Eigen::MatrixXd expected = (A * fine->domain().nodes).colwise() + b;
  EXPECT_LT((got - expected).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(FieldCopy, RejectsMismatchedComponents) {
  auto a = Block("a", Vec3::Zero(), Vec3::Ones(), 1);
  auto b = Block("b", Vec3::Zero(), Vec3::Ones(), 1);
  try {
    FieldCopy("c", *a, a->FindField("mass"), *b, b->FindField("external_force"),
              FieldCopy::Mapping::kAuto, 1.0);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("component counts differ (1 vs 3)"));
  }
}

TEST(BoundaryCoupling, FindsTheSharedInterface) {
  auto top = Block("top", Vec3(0, 0, 1), Vec3(1, 1, 2), 2);
  auto bottom = Block("bottom", Vec3(0, 0, 0), Vec3(1, 1, 1), 2);
  BoundaryCoupling coupling("glue", *top, *bottom, std::nullopt, -1);
  EXPECT_EQ(coupling.interface_vertices().size(), 9u);  // the 3x3 nodes of the z = 1 face
}

TEST(BoundaryCoupling, HangingBlockLoadsTheFixedBlockWithItsWeight) {
  // A block fixed at its top carries a second block glued below it through the connector. At
  // rest, the reactions at the top clamp must carry the weight of both blocks: the connector
  // transfers force without loss (transpose of the displacement interpolation).
  MassSpringParams params;
  params.stiffness = 2000;
  params.damping = 2;
  params.drag = 20;
  Kernel kernel;
  auto& top = kernel.coordinator().AddObject(
      Block("top", Vec3(0, 0, 0.1), Vec3(0.1, 0.1, 0.2), 2, params), 1e-4);
  auto& bottom = kernel.coordinator().AddObject(
      Block("bottom", Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), 3, params), 1e-4);
  const auto& v2n = top.boundary().vertex_to_node;
  std::vector<int> clamped;
  for (std::size_t j = 0; j < v2n.size(); ++j)
    if (top.domain().nodes(2, v2n[j]) > 0.2 - 1e-12) {
      top.boundary_conditions().Fix(static_cast<Index>(j));
      clamped.push_back(static_cast<int>(j));
    }
  ASSERT_EQ(clamped.size(), 9u);
  kernel.coordinator().AddConnector(
      std::make_unique<BoundaryCoupling>("glue", top, bottom, std::nullopt, -1));
  kernel.Initialize();
  RunResult result = kernel.Run(3.0);
  ASSERT_TRUE(result.ok()) << result.diagnostic;

  const double weight = 9.81 * (static_cast<MassSpring&>(top).masses().sum() +
                                static_cast<MassSpring&>(bottom).masses().sum());
  Eigen::MatrixXd reaction(3, top.boundary().num_vertices());
  top.ReadField(top.FindField("reaction_force"), reaction);
  double lift = 0;
  for (int j : clamped) lift += reaction(2, j);
  // After 3 s the motion has decayed (drag 20/s damps every mode at >= 10/s: e^-30); the staggered
  // exchange lags one step, which at rest changes nothing, so the balance holds to the solver's
  // residual motion.
  EXPECT_NEAR(lift, weight, 1e-6 * weight);
  // And the blocks did not separate: the interface vertices move together.
  Eigen::MatrixXd ut(3, top.boundary().num_vertices());
  top.ReadField(top.FindField("boundary_displacement"), ut);
  EXPECT_LT(ut.row(2).minCoeff(), -1e-5);  // it sagged
}

TEST(BoundaryCoupling, RejectsObjectsThatDoNotTouch) {
  auto a = Block("a", Vec3(0, 0, 0), Vec3(1, 1, 1), 1);
  auto b = Block("b", Vec3(0, 0, 2), Vec3(1, 1, 3), 1);
  try {
    BoundaryCoupling("glue", *a, *b, std::nullopt, -1);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("the objects share no interface"));
  }
}

}  // namespace
}  // namespace gipsi
