// The single-cell pacing driver, checked on a passive membrane whose response is known in
// closed form, and its protocol validation.

#include "gipsi/models/ep/single_cell.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

/// A passive membrane dV/dt = −(V − V_r)/τ + I_stim, integrated exactly (the stimulus is
/// constant over a step). Under a stimulus A from rest, V = V_r + Aτ(1 − e^(−t/τ)); afterwards
/// it relaxes back with time constant τ.
class PassiveMembrane final : public CellModel {
 public:
  static constexpr double kRest = -80.0, kTau = 10.0;
  PassiveMembrane() : CellModel({{"V", "mV"}, {"q", "1"}}, {kRest, 0.0}, 0) {}
  std::string_view type_name() const override { return "PassiveMembrane"; }
  std::string_view scheme() const override { return "exact"; }
  CellStimulus default_stimulus() const override { return {20.0, 2.0}; }

 protected:
  void DoStep(const CellStateView& s, std::size_t begin, std::size_t end, double dt,
              const double* i_stim) const override {
    for (std::size_t i = begin; i < end; ++i) {
      const double v_inf = kRest + kTau * (i_stim ? i_stim[i] : 0.0);
      s.var(0)[i] = v_inf + (s.var(0)[i] - v_inf) * std::exp(-dt / kTau);
      s.var(1)[i] += dt;  // elapsed time, to check the number of steps
    }
  }
  void DoCalcIonicCurrent(const ConstCellStateView& s, std::size_t begin, std::size_t end,
                          double* i_ion) const override {
    for (std::size_t i = begin; i < end; ++i) i_ion[i] = (s.var(0)[i] - kRest) / kTau;
  }
};

PacingProtocol Protocol() {
  PacingProtocol p;
  p.bcl = 100.0;
  p.beats = 3;
  p.dt = 0.01;
  p.stim_amplitude = 20.0;
  p.stim_duration = 2.0;
  p.apd_percent = 50.0;
  p.activation_threshold = -60.0;
  return p;
}

TEST(PaceSingleCell, BiomarkersMatchThePassiveMembraneInClosedForm) {
  PassiveMembrane model;
  const PacingProtocol p = Protocol();
  const SingleCellResult r = PaceSingleCell(model, p);
  const double a = p.stim_amplitude, tau = PassiveMembrane::kTau, rest = PassiveMembrane::kRest;
  const double peak = rest + a * tau * (1.0 - std::exp(-p.stim_duration / tau));
  const double t_act = -tau * std::log(1.0 - (p.activation_threshold - rest) / (a * tau));
  const double level = peak - 0.5 * (peak - rest);
  const double t_rep = p.stim_duration + tau * std::log((peak - rest) / (level - rest));
  ASSERT_EQ(r.beats.size(), 3u);
  for (const BeatMetrics& b : r.beats) {
    SCOPED_TRACE(b.beat);
    EXPECT_DOUBLE_EQ(b.start, 100.0 * static_cast<double>(b.beat));
    // Each beat starts 98 ms after the previous stimulus: e^(−9.8) of the excursion remains.
    EXPECT_NEAR(b.rest, rest, b.beat == 0 ? 0.0 : 0.01);
    EXPECT_NEAR(b.peak, peak, 0.01);
    // Linear interpolation between samples: errors O(dt²) ≪ 1e-3 ms.
    EXPECT_NEAR(b.activation - b.start, t_act, 1e-3);
    EXPECT_NEAR(b.repolarisation - b.start, t_rep, 1e-3);
    EXPECT_NEAR(b.apd, t_rep - t_act, 1e-3);
    // Steepest at the stimulus onset: (V(dt) − V(0))/dt ≈ A.
    EXPECT_NEAR(b.dvdt_max, a, 0.02);
  }
  // 3 beats of 100 ms: 30 000 steps.
  EXPECT_NEAR(r.final_state[1], 300.0, 1e-9);
}

TEST(PaceSingleCell, SubthresholdBeatsReportRangeButNoActivation) {
  PassiveMembrane model;
  PacingProtocol p = Protocol();
  p.stim_amplitude = 5.0;  // peaks at −70.9 mV, below the −60 mV threshold
  const SingleCellResult r = PaceSingleCell(model, p);
  for (const BeatMetrics& b : r.beats) {
    EXPECT_FALSE(b.activated());
    EXPECT_TRUE(std::isnan(b.apd));
    EXPECT_NEAR(b.peak, -80.0 + 50.0 * (1.0 - std::exp(-0.2)), 0.01);
    EXPECT_NEAR(b.rest, -80.0, 0.01);
  }
}

TEST(PaceSingleCell, RecordsEveryKthStepAndSamplesTheFullState) {
  PassiveMembrane model;
  PacingProtocol p = Protocol();
  p.beats = 1;
  p.record_every = 50;
  std::vector<double> times;
  std::size_t widths = 0;
  const SingleCellResult r = PaceSingleCell(
      model, p, {},
      [&](double t, std::span<const double> s) {
        times.push_back(t);
        widths += s.size();
      },
      300);
  // 10 000 steps: samples at steps 0, 50, …, 10 000.
  ASSERT_EQ(r.time.size(), 201u);
  EXPECT_EQ(r.voltage.size(), 201u);
  EXPECT_DOUBLE_EQ(r.time[1], 0.5);
  EXPECT_DOUBLE_EQ(r.time.back(), 100.0);
  EXPECT_DOUBLE_EQ(r.voltage.front(), -80.0);
  // Callback every 300 steps and at the end: 0, 3, …, 99 ms and 100 ms.
  ASSERT_EQ(times.size(), 35u);
  EXPECT_DOUBLE_EQ(times[1], 3.0);
  EXPECT_DOUBLE_EQ(times.back(), 100.0);
  EXPECT_EQ(widths, 2 * times.size());
}

TEST(PaceSingleCell, StartsFromTheGivenState) {
  PassiveMembrane model;
  PacingProtocol p = Protocol();
  p.beats = 1;
  p.stim_amplitude = 0.0;
  const std::vector<double> initial = {-70.0, 0.0};
  const SingleCellResult r = PaceSingleCell(model, p, initial);
  EXPECT_NEAR(r.final_state[0], -80.0 + 10.0 * std::exp(-10.0), 1e-9);
  EXPECT_THROW(PaceSingleCell(model, p, std::vector<double>{1.0}), InputError);
}

TEST(PaceSingleCell, RejectsInvalidProtocolsNamingTheField) {
  PassiveMembrane model;
  auto error = [&model](auto change) {
    PacingProtocol p = Protocol();
    change(p);
    try {
      PaceSingleCell(model, p);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error([](PacingProtocol& p) { p.bcl = -1; }),
            "pacing protocol: bcl: expected a positive cycle length [ms], got -1");
  EXPECT_THAT(error([](PacingProtocol& p) { p.beats = 0; }), HasSubstr("pacing protocol: beats"));
  EXPECT_THAT(error([](PacingProtocol& p) { p.dt = 200; }),
              HasSubstr("dt: expected a time step in (0, bcl = 100] ms, got 200"));
  EXPECT_THAT(error([](PacingProtocol& p) { p.dt = 0; }), HasSubstr("pacing protocol: dt"));
  EXPECT_THAT(error([](PacingProtocol& p) { p.stim_duration = -1; }), HasSubstr("stim_duration"));
  EXPECT_THAT(error([](PacingProtocol& p) { p.apd_percent = 100; }), HasSubstr("apd_percent"));
  EXPECT_THAT(error([](PacingProtocol& p) { p.record_every = -2; }), HasSubstr("record_every"));
}

TEST(CellTraceCsvHeader, NamesEachStateWithItsUnit) {
  PassiveMembrane model;
  EXPECT_EQ(CellTraceCsvHeader(model), "t_ms,V_mV,q");
}

}  // namespace
}  // namespace gipsi
