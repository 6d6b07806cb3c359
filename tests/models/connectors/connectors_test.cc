#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "gipsi/base/error.h"
#include "gipsi/core/kernel.h"
#include "gipsi/geometry/boundary.h"
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
  // Velocity [m/s] into force [N]: the scale carries the units, kg/s.
  FieldCopy copy("copy", *a, va, *b, b->FindField("external_force"), FieldCopy::Mapping::kAuto, 1.0,
                 "kg/s");
  EXPECT_EQ(copy.mapping(), FieldCopy::Mapping::kDirect);
  ASSERT_TRUE(copy.Fire(0).ok());
  Eigen::MatrixXd got(3, 27);
  b->ReadField(b->FindField("external_force"), got);
  EXPECT_EQ(got, v);
}

TEST(FieldCopy, UnitsAreCheckedAndConverted) {
  auto a = Block("a", Vec3::Zero(), Vec3::Ones(), 1);
  auto b = Block("b", Vec3::Zero(), Vec3::Ones(), 1);
  const FieldId velocity = a->FindField("velocity"), force = b->FindField("external_force");
  // 2 g/s is 0.002 kg/s: the factor carries the conversion into the target's units.
  FieldCopy grams("copy", *a, velocity, *b, force, FieldCopy::Mapping::kAuto, 2.0, "g/s");
  EXPECT_NEAR(grams.factor(), 0.002, 1e-15);
  // Same units, plain scale: the scale itself.
  FieldCopy same("copy", *a, velocity, *b, b->FindField("velocity"), FieldCopy::Mapping::kAuto,
                 3.0);
  EXPECT_EQ(same.factor(), 3.0);
  // Another dimension without scale units, or scale units that do not give the target's.
  auto error = [&](const std::string& units) {
    try {
      FieldCopy bad("copy", *a, velocity, *b, force, FieldCopy::Mapping::kAuto, 1.0, units);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("").find("the source is in [m/s] and the target in [N]; give \"scale\" with "
                           "the units"),
            std::string::npos)
      << error("");
  EXPECT_NE(error("kg").find("[m/s] times the scale's [kg] does not give the target's [N]"),
            std::string::npos)
      << error("kg");
  // The ports: the source read, the target written.
  ASSERT_EQ(grams.ports().size(), 2u);
  EXPECT_EQ(grams.ports()[0].object, a.get());
  EXPECT_EQ(grams.ports()[0].access, FieldAccess::kRead);
  EXPECT_EQ(grams.ports()[1].name, "external_force");
  EXPECT_EQ(grams.ports()[1].access, FieldAccess::kWrite);
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
                 fine->FindField("external_force"), FieldCopy::Mapping::kAuto, 1.0, "N*s/m");
  EXPECT_EQ(copy.mapping(), FieldCopy::Mapping::kBarycentric);
  ASSERT_TRUE(copy.Fire(0).ok());
  Eigen::MatrixXd got(3, fine->num_nodes());
  fine->ReadField(fine->FindField("external_force"), got);
  Eigen::MatrixXd expected = (A * fine->domain().nodes).colwise() + b;
  EXPECT_LT((got - expected).cwiseAbs().maxCoeff(), 1e-12);
}

/// A tet box with two node scalars: "marked" (no-data marker -1) and "plain" (no marker).
class MarkedFields final : public SimObject {
 public:
  MarkedFields(std::string name, int cells, double plain_marker_or_nan)
      : SimObject(std::move(name)) {
    auto mesh =
        std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3::Ones(), {cells, cells, cells}));
    SetGeometry(mesh, MakeBoundary(*mesh));
    FieldInfo marked{"marked", FieldLocation::kNode, 1, "s", FieldAccess::kReadWrite, "marked"};
    marked.no_data = -1;
    marked_id_ = DeclareField(marked);
    FieldInfo plain{"plain", FieldLocation::kNode, 1, "s", FieldAccess::kReadWrite, "plain"};
    if (!std::isnan(plain_marker_or_nan)) plain.no_data = plain_marker_or_nan;
    plain_id_ = DeclareField(plain);
    marked_ = plain_ = Eigen::RowVectorXd::Zero(mesh->num_nodes());
  }
  std::string_view type_name() const override { return "MarkedFields"; }
  const Points& domain_positions() const override { return domain().nodes; }
  Eigen::RowVectorXd marked_, plain_;

 protected:
  StepStatus DoStep(double, double) override { return StepStatus::Ok(); }
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override {
    out.row(0) = id == marked_id_ ? marked_ : plain_;
  }
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override {
    (id == marked_id_ ? marked_ : plain_) = in.row(0);
  }

 private:
  FieldId marked_id_, plain_id_;
};

TEST(FieldCopy, TheNoDataMarkerIsNeitherBlendedNorScaled) {
  // Activation times on a coarse box (-1: not activated, at x = 1), copied in ms (scale 1000)
  // onto a finer box: targets whose interpolation touches a marked node read a marker, never a
  // blend such as 0.5 * 0.04 + 0.5 * (-1) = -0.48 "ms"; the others read the interpolated value.
  for (const double target_marker : {std::nan(""), -7.0}) {
    MarkedFields coarse("coarse", 2, std::nan("")), fine("fine", 4, target_marker);
    const Points& x = coarse.domain().nodes;
    for (Index n = 0; n < x.cols(); ++n) coarse.marked_(n) = x(0, n) == 1.0 ? -1 : 0.08 * x(0, n);
    FieldCopy copy("copy", coarse, coarse.FindField("marked"), fine, fine.FindField("plain"),
                   FieldCopy::Mapping::kAuto, 1000.0);
    ASSERT_EQ(copy.mapping(), FieldCopy::Mapping::kBarycentric);
    ASSERT_TRUE(copy.Fire(0).ok());
    const double marker = std::isnan(target_marker) ? -1 : target_marker;
    const Points& y = fine.domain().nodes;
    int marked = 0;
    for (Index n = 0; n < y.cols(); ++n) {
      if (y(0, n) > 0.5 + 1e-12) {  // in the cells next to x = 1: touches a marked node
        EXPECT_EQ(fine.plain_(n), marker) << "node at x = " << y(0, n);
        ++marked;
      } else {
        EXPECT_NEAR(fine.plain_(n), 1000 * 0.08 * y(0, n), 1e-9) << "node at x = " << y(0, n);
      }
    }
    EXPECT_EQ(marked, 25 * 2);  // the fine box's planes x = 0.75 and x = 1
  }
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
