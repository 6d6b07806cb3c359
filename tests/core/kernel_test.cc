#include "gipsi/core/kernel.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/test_objects.h"
#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/core/aggregate.h"
#include "gipsi/core/connector.h"
#include "gipsi/models/connectors/field_copy.h"

namespace gipsi {
namespace {

using testing::CountingObject;
using ::testing::HasSubstr;

/// Records the times it is notified at and whether Finish was called.
class Recorder final : public Observer {
 public:
  explicit Recorder(std::vector<double>& times, bool& finished)
      : times_(times), finished_(finished) {}
  void Observe(const Kernel&, double t) override { times_.push_back(t); }
  void Finish(const Kernel&) override { finished_ = true; }

 private:
  std::vector<double>& times_;
  bool& finished_;
};

TEST(Kernel, SubStepsEachObjectAtItsOwnRate) {
  Kernel kernel;
  auto& slow = static_cast<CountingObject&>(
      kernel.coordinator().AddObject(std::make_unique<CountingObject>("slow"), 1e-3));
  auto& fast = static_cast<CountingObject&>(
      kernel.coordinator().AddObject(std::make_unique<CountingObject>("fast"), 1e-4));
  kernel.Initialize();  // macro step = largest dt = 1 ms
  EXPECT_EQ(kernel.macro_dt(), 1e-3);
  EXPECT_EQ(kernel.coordinator().object_substeps(1), 10);
  RunResult result = kernel.Run(0.05);
  ASSERT_TRUE(result.ok()) << result.diagnostic;
  EXPECT_EQ(slow.steps(), 50);
  EXPECT_EQ(fast.steps(), 500);
  EXPECT_EQ(result.macro_steps, 50);
  // Clocks are re-synchronised to the macro grid, so 500 sub-steps leave no round-off.
  EXPECT_EQ(fast.time(), kernel.time());
  EXPECT_DOUBLE_EQ(kernel.time(), 0.05);
}

TEST(Kernel, RejectsTimeStepThatDoesNotDivideMacroStep) {
  Kernel kernel;
  kernel.coordinator().AddObject(std::make_unique<CountingObject>("a"), 1e-3);
  kernel.coordinator().AddObject(std::make_unique<CountingObject>("b"), 3e-4);
  try {
    kernel.Initialize();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("object 'b': its time step 0.0003 s does not divide the "
                                    "macro step 0.001 s"));
  }
}

TEST(Kernel, ScheduledEventFiresAtItsTime) {
  Kernel kernel;
  auto& object = static_cast<CountingObject&>(
      kernel.coordinator().AddObject(std::make_unique<CountingObject>("a"), 1e-3));
  double fired_at = -1;
  std::int64_t steps_before = -1;
  kernel.ScheduleEvent({0.005, "test event", [&](Kernel& k) {
                          fired_at = k.time();
                          steps_before = object.steps();
                        }});
  kernel.Initialize();
  ASSERT_TRUE(kernel.Run(0.01).ok());
  EXPECT_DOUBLE_EQ(fired_at, 0.005);
  EXPECT_EQ(steps_before, 5);  // it fires at the start of the macro step beginning at 5 ms
  ASSERT_EQ(kernel.fired_events().size(), 1u);
  EXPECT_EQ(kernel.fired_events()[0].second, "test event");
}

TEST(Kernel, EventsBetweenMacroStepsFireAtTheNextOne) {
  Kernel kernel;
  kernel.coordinator().AddObject(std::make_unique<CountingObject>("a"), 1e-3);
  std::vector<double> fired;
  for (double t : {0.0025, 0.0, 0.0021})
    kernel.ScheduleEvent({t, "e", [&fired](Kernel& k) { fired.push_back(k.time()); }});
  kernel.Initialize();
  ASSERT_TRUE(kernel.Run(0.01).ok());
  ASSERT_EQ(fired.size(), 3u);
  EXPECT_DOUBLE_EQ(fired[0], 0.0);
  EXPECT_DOUBLE_EQ(fired[1], 0.003);
  EXPECT_DOUBLE_EQ(fired[2], 0.003);
}

TEST(Kernel, DivergingObjectStopsRunWithDiagnosticAndKeepsOutputs) {
  Kernel kernel;
  kernel.coordinator().AddObject(std::make_unique<CountingObject>("healthy"), 1e-3);
  kernel.coordinator().AddObject(std::make_unique<CountingObject>("tissue", 13), 1e-4);
  std::vector<double> times;
  bool finished = false;
  kernel.AddObserver(std::make_unique<Recorder>(times, finished));
  kernel.Initialize();
  RunResult result = kernel.Run(1.0);
  EXPECT_EQ(result.outcome, RunResult::Outcome::kDiverged);
  EXPECT_THAT(result.diagnostic, HasSubstr("object 'tissue' diverged"));
  EXPECT_THAT(result.diagnostic, HasSubstr("test divergence"));
  EXPECT_THAT(result.diagnostic, HasSubstr("item 7"));
  // Sub-step 13 of the fast object lies in macro step 1 (t in [1 ms, 2 ms)).
  EXPECT_THAT(result.diagnostic, HasSubstr("at t = 0.0012 s"));
  EXPECT_EQ(result.macro_steps, 1);
  // The observer saw t = 0 and t = 1 ms, and was finished (files flushed).
  EXPECT_EQ(times.size(), 2u);
  EXPECT_TRUE(finished);
}

/// A connector that breaks Connector's never-throw contract (as a plugin's or a Python
/// object's field read can).
class ThrowingConnector final : public Connector {
 public:
  ThrowingConnector() : Connector("thrower") {}
  std::string_view type_name() const override { return "Throwing"; }
  void SaveConnectorState(StateWriter&) const override {}
  void RestoreConnectorState(StateReader&) override {}

 protected:
  StepStatus DoFire(double t) override {
    if (t > 2.5e-3) throw std::runtime_error("read('x') returned 2 values, expected 1");
    return StepStatus::Ok();
  }
};

TEST(Kernel, AnExceptionInAMacroStepStopsTheRunNamingTheStepAndTheReason) {
  Kernel kernel;
  kernel.coordinator().AddObject(std::make_unique<CountingObject>("a"), 1e-3);
  kernel.coordinator().AddConnector(std::make_unique<ThrowingConnector>());
  kernel.Initialize();
  const RunResult result = kernel.Run(0.01);
  EXPECT_EQ(result.outcome, RunResult::Outcome::kStopped);
  EXPECT_EQ(result.diagnostic,
            "the macro step at t = 0.003 s could not be done: read('x') returned 2 values, "
            "expected 1");
  EXPECT_EQ(kernel.macro_steps(), 3);
}

TEST(Kernel, ARetryPolicyOverAnObjectWithoutCheckpointsSaysSo) {
  Kernel kernel;
  kernel.coordinator().AddObject(std::make_unique<CountingObject>("a"), 1e-3);
  kernel.SetFailurePolicy(FailurePolicy{.max_halvings = 2});
  kernel.Initialize();
  const RunResult result = kernel.Run(0.01);
  EXPECT_EQ(result.outcome, RunResult::Outcome::kStopped);
  EXPECT_THAT(result.diagnostic,
              HasSubstr("the macro step at t = 0 s could not be done: the failure policy needs "
                        "checkpoints: "));
  EXPECT_THAT(result.diagnostic, HasSubstr("does not support checkpoints"));
}

struct TickState {
  std::int64_t ticks = 0;
  template <class Self, class Visitor>
  static void Fields(Self& s, Visitor& v) {
    v("ticks", s.ticks);
  }
};

/// Counts its steps in a checkpointable state; fails its `fail_at`-th step once, after
/// counting it (a failure that leaves the object changed, as a diverged Newton solve does).
class Ticker final : public SimObject {
 public:
  explicit Ticker(std::string name, std::int64_t fail_at = -1)
      : SimObject(std::move(name)), fail_at_(fail_at) {
    BindState(state_);
  }
  std::string_view type_name() const override { return "Ticker"; }
  const Points& domain_positions() const override { return positions_; }
  std::int64_t ticks() const { return state_.ticks; }

 protected:
  StepStatus DoStep(double, double) override {
    if (++state_.ticks == fail_at_ && !failed_) {
      failed_ = true;
      return StepStatus::Failed("test failure");
    }
    return StepStatus::Ok();
  }
  void DoReadField(FieldId, Eigen::Ref<Eigen::MatrixXd>) const override {}
  void DoWriteField(FieldId, const Eigen::Ref<const Eigen::MatrixXd>&) override {}

 private:
  TickState state_;
  std::int64_t fail_at_;
  bool failed_ = false;
  Points positions_ = Points(3, 0);
};

TEST(Kernel, AfterAStepFailedPartWayItRefusesToGoOnUntilACheckpointIsRestored) {
  Kernel kernel;
  auto& a =
      static_cast<Ticker&>(kernel.coordinator().AddObject(std::make_unique<Ticker>("a"), 1e-3));
  auto& b =
      static_cast<Ticker&>(kernel.coordinator().AddObject(std::make_unique<Ticker>("b", 3), 1e-3));
  kernel.Initialize();
  StateWriter start;
  kernel.SaveState(start);
  RunResult result = kernel.Run(0.01);
  ASSERT_EQ(result.outcome, RunResult::Outcome::kDiverged);
  // In the macro step at t = 2 ms, a stepped (3 ticks) and b failed its 3rd: the objects
  // disagree, so stepping on would step a twice.
  EXPECT_EQ(a.ticks(), 3);
  EXPECT_EQ(kernel.broken(), "object 'b' failed inside the macro step at t = 0.002 s");
  result = kernel.Run(0.01);
  EXPECT_EQ(result.outcome, RunResult::Outcome::kStopped);
  EXPECT_EQ(result.diagnostic,
            "the simulation cannot go on from t = 0.002 s: object 'b' failed inside the macro "
            "step at t = 0.002 s; restore a checkpoint to continue");
  EXPECT_EQ(a.ticks(), 3);  // nothing stepped
  StateReader in(start.bytes(), "start");
  kernel.RestoreState(in);
  EXPECT_EQ(kernel.broken(), "");
  result = kernel.Run(0.01);
  EXPECT_EQ(result.outcome, RunResult::Outcome::kCompleted) << result.diagnostic;
  EXPECT_EQ(a.ticks(), 10);
  EXPECT_EQ(b.ticks(), 10);
}

TEST(Kernel, WithTheRetryPolicyAFailedStepIsRolledBackAndTheRunMayGoOn) {
  Kernel kernel;
  auto& a =
      static_cast<Ticker&>(kernel.coordinator().AddObject(std::make_unique<Ticker>("a"), 1e-3));
  kernel.coordinator().AddObject(std::make_unique<Ticker>("b", 3), 1e-3);
  kernel.SetFailurePolicy(FailurePolicy{.max_halvings = 1});
  kernel.Initialize();
  // b fails once; the halved retry succeeds, so the run completes.
  EXPECT_EQ(kernel.Run(0.01).outcome, RunResult::Outcome::kCompleted);
  EXPECT_EQ(kernel.broken(), "");
  EXPECT_EQ(kernel.retried_steps(), 1);
  EXPECT_EQ(a.ticks(), 11);  // 2 + 2 halves + 7
}

TEST(Kernel, ACheckpointRefusedBeforeTheObjectsLeavesTheSimulationAsItWas) {
  Kernel other;
  other.coordinator().AddObject(std::make_unique<Ticker>("a"), 1e-3);
  other.ScheduleEvent({0.5, "an event this scene lacks", [](Kernel&) {}});
  other.Initialize();
  other.Run(0.004);
  StateWriter saved;
  other.SaveState(saved);

  Kernel kernel;
  auto& a =
      static_cast<Ticker&>(kernel.coordinator().AddObject(std::make_unique<Ticker>("a"), 1e-3));
  kernel.Initialize();
  kernel.Run(0.002);
  StateReader in(saved.bytes(), "other");
  EXPECT_THROW(kernel.RestoreState(in), InputError);
  EXPECT_EQ(kernel.time(), 0.002);
  EXPECT_EQ(a.ticks(), 2);
  EXPECT_EQ(kernel.broken(), "");
  EXPECT_EQ(kernel.Run(0.005).outcome, RunResult::Outcome::kCompleted);
  EXPECT_EQ(a.ticks(), 5);
}

TEST(Kernel, ConnectorFiresEveryNMacroSteps) {
  Kernel kernel;
  auto& a = kernel.coordinator().AddObject(std::make_unique<CountingObject>("a"), 1e-3);
  auto& b = kernel.coordinator().AddObject(std::make_unique<CountingObject>("b"), 1e-3);
  auto& connector = kernel.coordinator().AddConnector(
      std::make_unique<FieldCopy>("copy", a, a.FindField("value"), b, b.FindField("value"),
                                  FieldCopy::Mapping::kAuto, 2.0),
      3);
  kernel.Initialize();
  ASSERT_TRUE(kernel.Run(0.01).ok());
  EXPECT_EQ(connector.fire_count(), 4);  // macro steps 0, 3, 6, 9
}

TEST(Coordinator, OrderMustNameEveryObjectAndConnectorOnce) {
  Coordinator c;
  c.AddObject(std::make_unique<CountingObject>("a"), 1e-3);
  c.AddObject(std::make_unique<CountingObject>("b"), 1e-3);
  EXPECT_THROW(c.SetOrder({"a"}), InputError);
  EXPECT_THROW(c.SetOrder({"a", "b", "a"}), InputError);
  try {
    c.SetOrder({"a", "bb"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("no object or connector named 'bb' (did you mean 'b'?)"));
  }
  EXPECT_NO_THROW(c.SetOrder({"b", "a"}));
}

TEST(Coordinator, RejectsDuplicateNames) {
  Coordinator c;
  c.AddObject(std::make_unique<CountingObject>("a"), 1e-3);
  EXPECT_THROW(c.AddObject(std::make_unique<CountingObject>("a"), 1e-3), InputError);
}

TEST(Kernel, DivergenceInsideAnAggregateNamesThePart) {
  Coordinator parts;
  parts.AddObject(std::make_unique<testing::CountingObject>("muscle"), 1e-3);
  parts.AddObject(std::make_unique<testing::CountingObject>("blood", 3), 1e-3);
  parts.Prepare(1e-3);
  Kernel kernel;
  kernel.coordinator().AddObject(std::make_unique<AggregateObject>("heart", std::move(parts)),
                                 1e-3);
  kernel.Initialize();
  RunResult result = kernel.Run(1.0);
  EXPECT_EQ(result.outcome, RunResult::Outcome::kDiverged);
  EXPECT_THAT(result.diagnostic, ::testing::HasSubstr("object 'heart' (part 'blood') diverged"));
  EXPECT_EQ(&kernel.FindObject("heart.blood"), kernel.coordinator().object(0).FindPart("blood"));
}

/// An object whose `request_at`-th step asks the kernel to stop in its middle and then polls its
/// stop token, as a long step (Newton iterations, load increments) does.
class LongStepObject final : public SimObject {
 public:
  LongStepObject(std::string name, Kernel& kernel, std::int64_t request_at)
      : SimObject(std::move(name)), kernel_(kernel), request_at_(request_at) {}
  std::string_view type_name() const override { return "LongStep"; }
  const Points& domain_positions() const override { return positions_; }
  int polls_after_request = 0;

 protected:
  StepStatus DoStep(double, double) override {
    for (int iteration = 0; iteration < 100; ++iteration) {
      if (step_count() + 1 == request_at_ && iteration == 5) kernel_.RequestStop();
      if (stop_token().stop_requested()) {
        ++polls_after_request;
        return StepStatus::Stopped();
      }
    }
    return StepStatus::Ok();
  }
  void DoReadField(FieldId, Eigen::Ref<Eigen::MatrixXd>) const override {}
  void DoWriteField(FieldId, const Eigen::Ref<const Eigen::MatrixXd>&) override {}

 private:
  Kernel& kernel_;
  std::int64_t request_at_;
  Points positions_ = Points(3, 0);
};

TEST(Kernel, AStopRequestReachesInsideAStepAlsoInAnAggregate) {
  // The request is made inside the 3rd step of a part of an aggregate: the kernel hands its
  // stop token down through the aggregate, the part abandons its step at its next poll, and
  // the run ends "stopped on request" after 2 completed macro steps.
  Kernel kernel;
  Coordinator parts;
  parts.AddObject(std::make_unique<CountingObject>("ep"), 1e-3);
  auto& muscle = static_cast<LongStepObject&>(
      parts.AddObject(std::make_unique<LongStepObject>("muscle", kernel, 3), 1e-3));
  parts.Prepare(1e-3);
  kernel.coordinator().AddObject(std::make_unique<AggregateObject>("heart", std::move(parts)),
                                 1e-3);
  kernel.Initialize();
  const RunResult result = kernel.Run(1.0);
  EXPECT_EQ(result.outcome, RunResult::Outcome::kStopped);
  EXPECT_EQ(result.macro_steps, 2);
  EXPECT_EQ(muscle.polls_after_request, 1);
  EXPECT_EQ(result.diagnostic,
            "stopped on request at t = 0.002 s, inside the step of object 'heart' (abandoned); "
            "outputs written up to t = 0.002 s are kept");
}

}  // namespace
}  // namespace gipsi
