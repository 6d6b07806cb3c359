// The closed loop LA → mitral → LV → aortic → aorta → peripheral → veins → LA with prescribed
// elastances (the "closed_loop" preset, i.e. the default parameters): blood volume conserved
// to round-off, convergence to a periodic state, valve events in the physiological order
// every beat, and physiological pressures.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "models/circulation/circulation_test_util.h"

namespace gipsi {
namespace {

constexpr double kPeriod = 0.8;  // the preset's heart period [s]
constexpr int kBeats = 20;
constexpr int kStepsPerBeat = 800;  // object steps of 1 ms

struct BeatSummary {
  double aortic_max = -1e300, aortic_min = 1e300;
  double lv_max_volume = -1e300, lv_min_volume = 1e300;
  double lv_max_pressure = -1e300;
};

struct ClosedLoopRun {
  std::vector<BeatSummary> beats;
  std::vector<VecX> state_at_beat_start;  // state at t = kT, k = 0..kBeats
  std::vector<double> total_volume;       // every step
  std::vector<ValveEvent> events;
  std::vector<std::string> valve_names;
  std::int64_t accepted = 0;
};

// Runs the preset once for all tests (a few thousand adaptive steps; well under a second).
const ClosedLoopRun& RunClosedLoop() {
  static const ClosedLoopRun run = [] {
    SceneHolder holder(R"({
      "objects": {"blood": {"type": "Circulation", "preset": "closed_loop", "dt": "1 ms",
                            "log_events": false}},
      "schedule": {"end": "16 s"}})");
    Circulation& blood = holder.Object("blood");
    ClosedLoopRun r;
    const int lv = blood.FindCompartment("lv"), aorta = blood.FindCompartment("aorta");
    r.state_at_beat_start.push_back(blood.state());
    r.total_volume.push_back(blood.total_volume());
    for (int beat = 0; beat < kBeats; ++beat) {
      BeatSummary s;
      for (int k = 0; k < kStepsPerBeat; ++k) {
        const StepStatus status = blood.Step(1e-3);
        EXPECT_TRUE(status.ok()) << status.what;
        if (!status.ok()) return r;
        s.aortic_max = std::max(s.aortic_max, blood.pressure(aorta));
        s.aortic_min = std::min(s.aortic_min, blood.pressure(aorta));
        s.lv_max_volume = std::max(s.lv_max_volume, blood.volume(lv));
        s.lv_min_volume = std::min(s.lv_min_volume, blood.volume(lv));
        s.lv_max_pressure = std::max(s.lv_max_pressure, blood.pressure(lv));
        r.total_volume.push_back(blood.total_volume());
      }
      r.beats.push_back(s);
      r.state_at_beat_start.push_back(blood.state());
    }
    r.events = blood.valve_events().Events();
    for (std::size_t k = 0; k < blood.circuit().valves().size(); ++k)
      r.valve_names.push_back(blood.valve_name(static_cast<int>(k)));
    r.accepted = blood.accepted_steps();
    return r;
  }();
  return run;
}

// Every flow leaves one compartment and enters another, so Σ V changes only by round-off:
// at most a few ulps of the total per adaptive step (each of the 4 compartment updates rounds
// once, each relative error ≤ 2^-53). The bound accepted × 4 × 2^-53 × V_total is the
// worst-case linear accumulation; integration error (1e-7 relative) would be far larger.
TEST(ClosedLoop, ConservesBloodVolumeToRoundOff) {
  const ClosedLoopRun& run = RunClosedLoop();
  ASSERT_EQ(run.beats.size(), static_cast<std::size_t>(kBeats));
  const double v0 = run.total_volume.front();
  const double bound =
      static_cast<double>(run.accepted) * 4 * std::numeric_limits<double>::epsilon() / 2 * v0;
  double drift = 0;
  for (double v : run.total_volume) drift = std::max(drift, std::abs(v - v0));
  EXPECT_LE(drift, bound) << "drift " << drift << " m^3 over " << run.accepted << " steps";
  RecordProperty("volume_drift_m3", fmt::format("{:.3g} (bound {:.3g})", drift, bound));
}

// The state at the start of beat k+1 minus that of beat k shrinks geometrically (the slowest
// mode is the arterial–venous exchange through R_p, τ ≈ R_p C_a C_v/(C_a + C_v) ≈ 1.5 s, i.e.
// a factor e^{−0.8/1.5} ≈ 0.6 per beat). After 20 beats the change of every compartment
// volume over one beat is below 1e-4 of the total volume (0.08 mL), and it decreases.
TEST(ClosedLoop, ConvergesToAPeriodicState) {
  const ClosedLoopRun& run = RunClosedLoop();
  ASSERT_EQ(run.state_at_beat_start.size(), static_cast<std::size_t>(kBeats + 1));
  const double v0 = run.total_volume.front();
  auto change = [&](int k) {
    return (run.state_at_beat_start[k + 1] - run.state_at_beat_start[k])
        .head(4)
        .cwiseAbs()
        .maxCoeff();
  };
  EXPECT_LT(change(kBeats - 1), 1e-4 * v0);
  EXPECT_LT(change(kBeats - 1), change(kBeats / 2));
}

// Each beat: mitral closes, aortic opens, aortic closes, mitral opens — and nothing else.
// From the first mitral closure on, events come in exactly that cycle of four, one cycle per
// beat (the mitral closure of beat k lies in [kT, (k+1)T)).
TEST(ClosedLoop, ValveEventsFollowThePhysiologicalOrderEveryBeat) {
  const ClosedLoopRun& run = RunClosedLoop();
  int mitral = -1, aortic = -1;
  for (std::size_t k = 0; k < run.valve_names.size(); ++k) {
    if (run.valve_names[k] == "mitral") mitral = static_cast<int>(k);
    if (run.valve_names[k] == "aortic") aortic = static_cast<int>(k);
  }
  ASSERT_GE(mitral, 0);
  ASSERT_GE(aortic, 0);
  std::size_t first = 0;
  while (first < run.events.size() &&
         !(run.events[first].valve == mitral && run.events[first].state == ValveState::kClosed))
    ++first;
  const struct {
    int valve;
    ValveState state;
  } cycle[4] = {{mitral, ValveState::kClosed},
                {aortic, ValveState::kOpen},
                {aortic, ValveState::kClosed},
                {mitral, ValveState::kOpen}};
  ASSERT_GE(run.events.size() - first, static_cast<std::size_t>(4 * (kBeats - 1)));
  const int first_beat = static_cast<int>(std::floor(run.events[first].time / kPeriod));
  int beats_seen = 0;
  for (std::size_t i = first; i < run.events.size(); ++i) {
    const auto& e = run.events[i];
    const auto& want = cycle[(i - first) % 4];
    EXPECT_EQ(e.valve, want.valve) << "event " << i << " at t = " << e.time;
    EXPECT_EQ(e.state, want.state) << "event " << i << " at t = " << e.time;
    if ((i - first) % 4 == 0) {
      const int beat = static_cast<int>(std::floor(e.time / kPeriod));
      EXPECT_EQ(beat, first_beat + beats_seen) << "mitral closure at t = " << e.time;
      ++beats_seen;
    }
    if (i > first) {
      EXPECT_GT(e.time, run.events[i - 1].time);
    }
  }
  EXPECT_GE(beats_seen, kBeats - 1);
}

// With the default parameters the periodic state is physiological: aortic pressure about
// 120/80 mmHg (systolic in [110, 130], diastolic in [70, 90]) and an ejection fraction in
// 50–65 %, as the issue asks of the default demo.
TEST(ClosedLoop, DefaultParametersGivePhysiologicalPressures) {
  const ClosedLoopRun& run = RunClosedLoop();
  ASSERT_FALSE(run.beats.empty());
  const BeatSummary& b = run.beats.back();
  const double systolic = b.aortic_max / kMmHg, diastolic = b.aortic_min / kMmHg;
  const double edv = b.lv_max_volume / kMl, esv = b.lv_min_volume / kMl;
  const double ef = (edv - esv) / edv;
  EXPECT_GT(systolic, 110);
  EXPECT_LT(systolic, 130);
  EXPECT_GT(diastolic, 70);
  EXPECT_LT(diastolic, 90);
  EXPECT_GT(ef, 0.50);
  EXPECT_LT(ef, 0.65);
  RecordProperty("aortic_mmHg", std::to_string(systolic) + "/" + std::to_string(diastolic));
  RecordProperty("edv_esv_ef",
                 std::to_string(edv) + " " + std::to_string(esv) + " " + std::to_string(ef));
  std::printf("aortic %.1f/%.1f mmHg, LV peak %.1f mmHg, EDV %.1f mL, ESV %.1f mL, EF %.1f %%\n",
              systolic, diastolic, b.lv_max_pressure / kMmHg, edv, esv, 100 * ef);
}

}  // namespace
}  // namespace gipsi
