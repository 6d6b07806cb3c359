// Real-time pacing in the kernel (gipsi/core/pacing.h): an object on the wall clock is never
// stepped past it, the coordinator waits (the object itself does not sleep), and a stop request
// ends the wait.

#include "gipsi/core/pacing.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "gipsi/core/coordinator.h"
#include "test_objects.h"

namespace gipsi {
namespace {

using Clock = std::chrono::steady_clock;

/// An object whose time runs on the wall clock from its construction; it records, at each
/// step, how far the wall clock was behind the step's end (≤ 0 when paced).
class WallClockObject final : public SimObject, public WallClockPaced {
 public:
  explicit WallClockObject(std::string name) : SimObject(std::move(name)), start_(Clock::now()) {}
  std::string_view type_name() const override { return "WallClockObject"; }
  const Points& domain_positions() const override { return positions_; }
  double WallClockTime(double /*sim_time*/) const override {
    return std::chrono::duration<double>(Clock::now() - start_).count();
  }
  const std::vector<double>& lag() const { return lag_; }

 protected:
  StepStatus DoStep(double t, double dt) override {
    lag_.push_back((t + dt) - WallClockTime(t));
    return StepStatus::Ok();
  }
  void DoReadField(FieldId, Eigen::Ref<Eigen::MatrixXd>) const override {}
  void DoWriteField(FieldId, const Eigen::Ref<const Eigen::MatrixXd>&) override {}

 private:
  Clock::time_point start_;
  Points positions_;
  std::vector<double> lag_;
};

TEST(Pacing, AnObjectOnTheWallClockIsNeverSteppedPastIt) {
  Coordinator coordinator;
  auto& paced = static_cast<WallClockObject&>(
      coordinator.AddObject(std::make_unique<WallClockObject>("device"), 0.005));
  coordinator.AddObject(std::make_unique<testing::CountingObject>("tissue"), 0.01);
  coordinator.Prepare(0.01);
  for (int m = 0; m < 5; ++m) ASSERT_FALSE(coordinator.MacroStep(0.01 * m, m).has_value());
  // Every sub-step began once the object's wall clock had reached its end, so that clock shows
  // at least the 50 ms simulated (a lower bound from the waiting rule, not a timing
  // measurement; the clock started when the object was built).
  ASSERT_EQ(paced.lag().size(), 10u);
  for (double lag : paced.lag()) EXPECT_LE(lag, 0.0);
  EXPECT_GE(paced.WallClockTime(0.05), 0.05);
}

TEST(Pacing, AStopRequestEndsTheWait) {
  Coordinator coordinator;
  coordinator.AddObject(std::make_unique<WallClockObject>("device"), 1000.0);
  coordinator.Prepare(1000.0);
  std::atomic<bool> stop{false};
  coordinator.SetStopToken(StopToken(&stop));
  std::thread requester([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    stop = true;
  });
  // Without the stop request the step would wait 1000 s of wall clock.
  const auto start = Clock::now();
  (void)coordinator.MacroStep(0, 0);
  requester.join();
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - start).count(), 60.0);
}

}  // namespace
}  // namespace gipsi
