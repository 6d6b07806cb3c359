// SimObject::BindState: an object that declares its state value type gets checkpoints and
// copy-retries with no hook of its own, and StateRestored() after every restore. The same for
// connectors (Connector::BindState, BindNoState) and for a state gathered from several members
// (BindGatheredState).

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>

#include "gipsi/base/error.h"
#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/core/connector.h"
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

struct FilterState {
  double value = 0;
  std::int64_t fired = 0;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("value", s.value);
    v("fired", s.fired);
  }
};

/// A low-pass filter of its firing times: state that outlives a Fire. `bind` chooses how it
/// declares it: a bound value, nothing (it then loses its value on restore, which the test
/// uses only for the declaration), or only the checkpoint hooks.
class Filter final : public Connector {
 public:
  enum class Binding { kValue, kNone, kHooks };
  explicit Filter(Binding binding) : Connector("filter"), binding_(binding) {
    if (binding == Binding::kValue) BindState(state_);
    if (binding == Binding::kNone) BindNoState();
  }
  std::string_view type_name() const override { return "Filter"; }
  const FilterState& state() const { return state_; }
  void SaveConnectorState(StateWriter& out) const override {
    if (binding_ != Binding::kHooks) return Connector::SaveConnectorState(out);
    out.WriteDouble(state_.value);
    out.WriteInt(state_.fired);
  }
  void RestoreConnectorState(StateReader& in) override {
    if (binding_ != Binding::kHooks) return Connector::RestoreConnectorState(in);
    state_.value = in.ReadDouble();
    state_.fired = in.ReadInt();
  }

 protected:
  StepStatus DoFire(double t) override {
    state_.value = 0.5 * state_.value + 0.5 * t;
    ++state_.fired;
    return StepStatus::Ok();
  }

 private:
  Binding binding_;
  FilterState state_;
};

TEST(BindState, AConnectorsBoundValueIsCopiedBySnapshotsAndWrittenByCheckpoints) {
  for (Filter::Binding binding : {Filter::Binding::kValue, Filter::Binding::kHooks}) {
    Filter filter(binding);
    EXPECT_EQ(filter.state_is_value(), binding == Filter::Binding::kValue);
    ASSERT_TRUE(filter.Fire(0.1).ok());
    auto snapshot = filter.NewSnapshot();
    StateWriter out;
    filter.SaveState(out);
    const FilterState saved = filter.state();
    ASSERT_TRUE(filter.Fire(0.2).ok());
    ASSERT_TRUE(filter.Fire(0.3).ok());
    filter.RestoreSnapshot(*snapshot);
    EXPECT_EQ(FirstDifference(saved, filter.state()), "");
    EXPECT_EQ(filter.fire_count(), 1);
    ASSERT_TRUE(filter.Fire(0.2).ok());
    StateReader in(out.TakeBytes(), "filter.gck");
    filter.RestoreState(in);
    EXPECT_EQ(FirstDifference(saved, filter.state()), "");
    EXPECT_EQ(filter.fire_count(), 1);
  }
}

TEST(BindState, AConnectorWithNoStateWritesNothingOfItsOwn) {
  Filter none(Filter::Binding::kNone), hooks(Filter::Binding::kHooks);
  EXPECT_TRUE(none.state_is_value());
  StateWriter a, b;
  none.SaveState(a);
  hooks.SaveState(b);
  // The hooks write a double and an integer (two typed entries) that the no-state one does not.
  EXPECT_LT(a.TakeBytes().size(), b.TakeBytes().size());
  auto snapshot = none.NewSnapshot();
  ASSERT_TRUE(none.Fire(0.1).ok());
  none.RestoreSnapshot(*snapshot);
  EXPECT_EQ(none.fire_count(), 0);
}

struct PairState {
  static constexpr std::string_view kTag = "PairState";
  static constexpr std::uint32_t kVersion = 1;
  double a = 0;
  std::int64_t b = 0;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("a", s.a);
    v("b", s.b);
  }
};

/// State kept in two members, gathered into a PairState; `b` must stay below 100.
class Pair final : public SimObject {
 public:
  Pair() : SimObject("pair") {
    BindGatheredState<PairState>(
        [this](PairState& s) {
          s.a = a_;
          s.b = b_;
        },
        [this](const PairState& s) {
          if (s.b >= 100) throw InputError("b must stay below 100");
          a_ = s.a;
          b_ = s.b;
        });
  }
  std::string_view type_name() const override { return "Pair"; }
  const Points& domain_positions() const override { return positions_; }
  double a() const { return a_; }
  std::int64_t b() const { return b_; }
  void set_b(std::int64_t b) { b_ = b; }

 protected:
  StepStatus DoStep(double, double dt) override {
    a_ += dt;
    ++b_;
    return StepStatus::Ok();
  }
  void DoReadField(FieldId, Eigen::Ref<Eigen::MatrixXd>) const override {}
  void DoWriteField(FieldId, const Eigen::Ref<const Eigen::MatrixXd>&) override {}

 private:
  double a_ = 0;
  std::int64_t b_ = 0;
  Points positions_;
};

TEST(BindState, AGatheredStateIsCopiedInAndOutAndCheckedBeforeItReplacesAnything) {
  Pair pair;
  EXPECT_TRUE(pair.state_is_value());
  ASSERT_TRUE(pair.Step(0.25).ok());
  auto snapshot = pair.NewSnapshot();
  StateWriter good;
  pair.SaveState(good);
  ASSERT_TRUE(pair.Step(0.25).ok());
  pair.RestoreSnapshot(*snapshot);
  EXPECT_EQ(pair.a(), 0.25);
  EXPECT_EQ(pair.b(), 1);

  // A checkpoint holding a value the object refuses: the reader names the file, the object
  // keeps its state.
  pair.set_b(100);
  StateWriter bad;
  pair.SaveState(bad);
  pair.set_b(1);
  StateReader in(bad.TakeBytes(), "pair.gck");
  try {
    pair.RestoreState(in);
    FAIL() << "a refused value was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("pair.gck"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("b must stay below 100"), std::string::npos) << e.what();
  }
  EXPECT_EQ(pair.b(), 1);
  StateReader ok(good.TakeBytes(), "pair.gck");
  pair.RestoreState(ok);
  EXPECT_EQ(pair.b(), 1);
  EXPECT_EQ(pair.a(), 0.25);
}

}  // namespace
}  // namespace gipsi
