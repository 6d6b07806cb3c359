// SimObject::BindState: an object that declares its state value type gets checkpoints and
// copy-retries with no hook of its own, and StateRestored() after every restore.

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>

#include "gipsi/base/error.h"
#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/core/sim_object.h"

namespace gipsi {
namespace {

struct DecayState {
  VecX x = VecX::Zero(4);
  std::int64_t steps = 0;

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("x", s.x, Shape::kFixed);
    v("steps", s.steps);
  }
};

/// dx/dt = −k x by explicit Euler; `sum_` derives from the state (rebuilt on restore).
class Decay final : public SimObject {
 public:
  Decay() : SimObject("decay") {
    state_.x << 1.0, 0.5, -0.25, 2.0;
    sum_ = state_.x.sum();
    BindState(state_);
  }
  std::string_view type_name() const override { return "Decay"; }
  const Points& domain_positions() const override { return positions_; }
  const DecayState& state() const { return state_; }
  double sum() const { return sum_; }
  int restored() const { return restored_; }

 protected:
  StepStatus DoStep(double, double dt) override {
    state_.x -= dt * 0.7 * state_.x.cwiseProduct(state_.x.cwiseAbs().cwiseSqrt());
    ++state_.steps;
    sum_ = state_.x.sum();
    return StepStatus::Ok();
  }
  void StateRestored() override {
    sum_ = state_.x.sum();
    ++restored_;
  }
  void DoReadField(FieldId, Eigen::Ref<Eigen::MatrixXd>) const override {}
  void DoWriteField(FieldId, const Eigen::Ref<const Eigen::MatrixXd>&) override {}

 private:
  DecayState state_;
  double sum_ = 0;
  int restored_ = 0;
  Points positions_;
};

TEST(BindState, ASnapshotCopiesTheBoundValueAndSteppingAgainGivesTheSameBits) {
  Decay decay;
  auto snapshot = decay.NewSnapshot();
  decay.TakeSnapshot(*snapshot);
  for (int k = 0; k < 3; ++k) ASSERT_TRUE(decay.Step(0.01).ok());
  const DecayState first = decay.state();
  decay.RestoreSnapshot(*snapshot);
  EXPECT_EQ(decay.restored(), 1);
  EXPECT_EQ(decay.state().steps, 0);
  EXPECT_EQ(decay.sum(), decay.state().x.sum());  // derived data rebuilt
  for (int k = 0; k < 3; ++k) ASSERT_TRUE(decay.Step(0.01).ok());
  EXPECT_EQ(FirstDifference(first, decay.state()), "");
  EXPECT_EQ(decay.state().steps, 3);
}

TEST(BindState, ACheckpointWritesAndReadsTheBoundValue) {
  Decay decay;
  ASSERT_TRUE(decay.Step(0.01).ok());
  StateWriter out;
  decay.SaveState(out);
  const DecayState saved = decay.state();
  ASSERT_TRUE(decay.Step(0.01).ok());
  ASSERT_NE(FirstDifference(saved, decay.state()), "");

  StateReader in(out.TakeBytes(), "decay.gck");
  decay.RestoreState(in);
  EXPECT_EQ(FirstDifference(saved, decay.state()), "");
  EXPECT_EQ(decay.restored(), 1);
  EXPECT_EQ(decay.sum(), saved.x.sum());
}

}  // namespace
}  // namespace gipsi
