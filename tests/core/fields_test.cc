#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/core/boundary_conditions.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/models/mass_spring/mass_spring.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

std::unique_ptr<MassSpring> Cube() {
  return std::make_unique<MassSpring>(
      "cube", std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3(1, 1, 1), {2, 2, 2})),
      MassSpringParams{}, std::make_unique<SymplecticEuler>());
}

TEST(Fields, SetThenGetRoundTrips) {
  auto cube = Cube();
  FieldId velocity = cube->FindField("velocity");
  Eigen::MatrixXd in = Eigen::MatrixXd::Random(3, cube->FieldCount(velocity));
  cube->WriteField(velocity, in);
  Eigen::MatrixXd out(3, cube->FieldCount(velocity));
  cube->ReadField(velocity, out);
  EXPECT_EQ(in, out);
}

TEST(Fields, CountsFollowTheirLocation) {
  auto cube = Cube();
  EXPECT_EQ(cube->FieldCount(cube->FindField("position")), 27);
  EXPECT_EQ(cube->FieldCount(cube->FindField("reaction_force")), cube->boundary().num_vertices());
  EXPECT_EQ(cube->FieldCount(cube->FindField("kinetic_energy")), 1);
  EXPECT_EQ(cube->boundary().num_vertices(), 26);  // all but the centre node
}

TEST(Fields, UnknownNameListsTheFieldsAndSuggests) {
  auto cube = Cube();
  try {
    (void)cube->FindField("velocty");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("object 'cube' (MassSpring) has no field 'velocty' (did you "
                                    "mean 'velocity'?); its fields are: position, velocity"));
  }
}

// What probes read: the asked items (in any order, repeated) are ReadField's columns, bitwise,
// for a field stored in the object (FieldMemory) and for one computed on request.
TEST(Fields, ReadingItemsGivesThoseColumnsOfTheWholeField) {
  auto cube = Cube();
  cube->WriteField(cube->FindField("velocity"),
                   Eigen::MatrixXd::Random(3, cube->FieldCount(cube->FindField("velocity"))));
  const std::vector<int> items = {26, 3, 3, 0, 13};
  for (const char* name : {"position", "velocity", "displacement"}) {
    const FieldId id = cube->FindField(name);
    Eigen::MatrixXd whole(3, cube->FieldCount(id)), some(3, 5);
    cube->ReadField(id, whole);
    cube->ReadFieldItems(id, items, some);
    for (std::size_t k = 0; k < items.size(); ++k)
      EXPECT_EQ(some.col(static_cast<Index>(k)), whole.col(items[k])) << name << " item " << k;
  }
}

TEST(FieldsDeathTest, WrongSizeIsAProgrammerErrorThatAborts) {
  auto cube = Cube();
  Eigen::MatrixXd wrong(3, 5);
  EXPECT_DEATH(cube->ReadField(cube->FindField("position"), wrong), "is 3 by 27, buffer is 3 by 5");
  EXPECT_DEATH(cube->WriteField(cube->FindField("displacement"), wrong), "read-only");
  const std::vector<int> outside = {27};
  Eigen::MatrixXd one(3, 1);
  EXPECT_DEATH(cube->ReadFieldItems(cube->FindField("position"), outside, one),
               "has 27 items, asked for item 27");
}

TEST(BoundaryConditions, FixThenReleaseFreesTheAxes) {
  BoundaryConditions bcs(4, 2);
  bcs.Fix(1, 0b101);
  EXPECT_EQ(bcs.kind(1, 0), ConstraintKind::kDisplacement);
  EXPECT_EQ(bcs.kind(1, 1), ConstraintKind::kFree);
  EXPECT_EQ(bcs.kind(1, 2), ConstraintKind::kDisplacement);
  EXPECT_TRUE(bcs.any_constraint());
  bcs.Release(1);
  EXPECT_FALSE(bcs.any_constraint());
}

TEST(BoundaryConditions, CouplingLoadsAddToAppliedLoadsAndClear) {
  BoundaryConditions bcs(2, 1);
  bcs.SetForce(0, Vec3(1, 0, 0));
  bcs.AddCouplingForce(0, Vec3(0, 2, 0));
  bcs.AddCouplingForce(0, Vec3(0, 3, 0));
  EXPECT_EQ(bcs.force(0), Vec3(1, 5, 0));
  bcs.AddCouplingPressure(0, 7);
  EXPECT_TRUE(bcs.any_face_load());
  bcs.ClearCouplingLoads();
  EXPECT_EQ(bcs.force(0), Vec3(1, 0, 0));
  EXPECT_EQ(bcs.pressure(0), 0);
}

// SkipApplied reads conditions saved for a store of any size and says whether they apply
// anything: a free store's do not; a fixed vertex, a force or a pressure does.
TEST(BoundaryConditions, SkippingSavedConditionsTellsWhetherTheyApplyAnything) {
  auto skipped = [](const BoundaryConditions& bcs) {
    StateWriter out;
    bcs.SaveApplied(out);
    out.WriteInt(42);  // what follows is read next
    StateReader in(out.TakeBytes(), "bcs");
    const bool free = BoundaryConditions::SkipApplied(in);
    EXPECT_EQ(in.ReadInt(), 42);
    return free;
  };
  EXPECT_TRUE(skipped(BoundaryConditions(5, 3)));
  EXPECT_TRUE(skipped(BoundaryConditions(0, 0)));
  BoundaryConditions fixed(5, 3), loaded(5, 3), pressed(5, 3);
  fixed.Fix(4);
  loaded.SetForce(2, Vec3(0, 0, 1));
  pressed.SetPressure(1, 10);
  EXPECT_FALSE(skipped(fixed));
  EXPECT_FALSE(skipped(loaded));
  EXPECT_FALSE(skipped(pressed));
}

}  // namespace
}  // namespace gipsi
