// ten Tusscher–Panfilov 2006: action potentials of the three variants at 1 Hz, accuracy of the
// Rush–Larsen step against a 100× finer step, and of the voltage lookup table against exact
// evaluation.

#include "gipsi/models/ep/ten_tusscher_panfilov_2006.h"

#include <cmath>
#include <functional>

#include <gtest/gtest.h>

#include "gipsi/models/ep/lookup_table.h"
#include "models/ep/cell_test_util.h"

namespace gipsi {
namespace {

using testing::MakeCellModel;
using testing::Pace;
using testing::RmsDifference;

// Published ranges at 1 Hz pacing (ten Tusscher & Panfilov 2006, AJP Heart 291:H1088, and the
// CellML encodings): resting potential ≈ −85 mV (CellML initial value −85.23 mV epi, −86.71
// endo, −85.42 M); overshoot about +30 to +40 mV; epicardial APD90 ≈ 270–310 ms with the endo
// APD close to it and the M-cell APD clearly longer (Gks is a quarter of epi's). Measured here
// (dt 0.01 ms, 5th beat): epi rest −85.5 mV, peak 39.8 mV, APD90 306.8 ms, dV/dt max
// 386 mV/ms; endo −86.0 / 39.4 / 298.0; M −85.8 / 38.4 / 390.6. The peak of a 0.01 ms run is
// about 1 mV above the converged one (38.8 mV at dt 0.0001): the upstroke is under-resolved.
struct VariantCase {
  const char* variant;
  double rest_lo, rest_hi, apd_lo, apd_hi;
};

class TenTusscherVariant : public ::testing::TestWithParam<VariantCase> {};

INSTANTIATE_TEST_SUITE_P(Variants, TenTusscherVariant,
                         ::testing::Values(VariantCase{"epi", -86.5, -84.5, 270.0, 310.0},
                                           VariantCase{"endo", -87.0, -85.0, 270.0, 310.0},
                                           VariantCase{"M", -87.0, -84.5, 350.0, 420.0}),
                         [](const auto& info) { return std::string(info.param.variant); });

TEST_P(TenTusscherVariant, ActionPotentialAt1HzIsInThePublishedRanges) {
  const VariantCase& c = GetParam();
  auto model = MakeCellModel(std::string(R"({"model": "TenTusscherPanfilov2006", "variant": ")") +
                             c.variant + "\"}");
  const SingleCellResult r = Pace(*model, 0.01, 5);
  for (const BeatMetrics& b : r.beats) {
    SCOPED_TRACE(b.beat);
    EXPECT_GE(b.rest, c.rest_lo);
    EXPECT_LE(b.rest, c.rest_hi);
    EXPECT_GE(b.peak, 30.0);
    EXPECT_LE(b.peak, 42.0);
    EXPECT_GT(b.dvdt_max, 250.0);  // sodium upstroke (≈ 370–390 mV/ms here)
    EXPECT_LT(b.activation - b.start, 2.0);
    if (b.beat > 0) {  // the first beat from the CellML state is ~5 % shorter
      EXPECT_GE(b.apd, c.apd_lo);
      EXPECT_LE(b.apd, c.apd_hi);
    }
  }
  EXPECT_NEAR(r.beats[4].apd, r.beats[3].apd, 1.0);  // close to the 1 Hz steady state
}

// Large Ito (epi and M: Gto 0.294 mS/µF) gives the spike-and-dome shape: V falls to a notch
// after the upstroke and rises again to the dome; with endocardial Gto 0.073 the dip is small.
// Measured (dome − notch): epi 9.8, M 10.8, endo 2.5 mV. The M cell's small Gks makes its APD
// the longest (measured 391 vs 306 epi and 298 endo ms).
TEST(TenTusscherPanfilov2006, McellApdIsLongestAndEpicardiumHasANotch) {
  auto apd_and_notch = [](const char* variant) {
    auto model = MakeCellModel(std::string(R"({"model": "TenTusscherPanfilov2006", "variant": ")") +
                               variant + "\"}");
    const SingleCellResult r = Pace(*model, 0.01, 2, 10);
    // Second beat: the peak, the lowest V in the 30 ms after it (the notch), the highest V in
    // the 100 ms after the notch (the dome).
    std::size_t i = 0;
    while (r.time[i] < 1000.0) ++i;
    std::size_t peak = i;
    for (; r.time[i] < 1010.0; ++i)
      if (r.voltage[i] > r.voltage[peak]) peak = i;
    std::size_t notch = peak;
    for (i = peak; r.time[i] < r.time[peak] + 30.0; ++i)
      if (r.voltage[i] < r.voltage[notch]) notch = i;
    double dome = r.voltage[notch];
    for (i = notch; r.time[i] < r.time[notch] + 100.0; ++i) dome = std::max(dome, r.voltage[i]);
    return std::pair{r.beats[1].apd, dome - r.voltage[notch]};
  };
  const auto [epi_apd, epi_notch] = apd_and_notch("epi");
  const auto [endo_apd, endo_notch] = apd_and_notch("endo");
  const auto [m_apd, m_notch] = apd_and_notch("M");
  EXPECT_GT(m_apd, epi_apd + 50.0);
  EXPECT_GT(m_apd, endo_apd + 50.0);
  EXPECT_GT(epi_notch, 6.0);
  EXPECT_GT(m_notch, 6.0);
  EXPECT_LT(endo_notch, 4.0);
}

// Rush–Larsen for the gates + forward Euler elsewhere is first order. At dt = 0.01 ms the
// first 400 ms (a full action potential) agree with a run at dt = 0.0001 ms: measured APD90
// difference 0.021 %, V-trace RMS difference 0.11 mV (the upstroke, 0.014 ms later in the
// coarse run at ≈ 370 mV/ms, dominates). Bounds: 0.5 % and 1 mV. At dt = 0.02 ms the errors
// roughly double (0.044 %, 0.22 mV), as expected for a first-order scheme.
TEST(TenTusscherPanfilov2006, ProductionStepAgreesWithAHundredTimesFinerStep) {
  auto model = MakeCellModel(R"({"model": "TenTusscherPanfilov2006"})");
  const SingleCellResult fine = Pace(*model, 0.0001, 1, 200, 400.0);  // every 0.02 ms
  for (double dt : {0.01, 0.02}) {
    const SingleCellResult coarse = Pace(*model, dt, 1, std::lround(0.02 / dt), 400.0);
    ASSERT_EQ(coarse.voltage.size(), fine.voltage.size());
    EXPECT_NEAR(coarse.beats[0].apd / fine.beats[0].apd, 1.0, 0.005) << dt;
    EXPECT_LT(RmsDifference(coarse.voltage, fine.voltage), 1.0) << dt;
    EXPECT_NEAR(coarse.beats[0].rest, fine.beats[0].rest, 0.01) << dt;
    EXPECT_NEAR(coarse.beats[0].peak, fine.beats[0].peak, 3.0) << dt;
  }
}

// Largest interpolation error of each column of `table` at the grid midpoints, relative to the
// exact value with a floor of `floor` times the column's largest magnitude (1: absolute error
// relative to the scale; 1e-3 for terms that pass near zero), skipping the interval containing
// `skip` (a jump of the exact function).
std::vector<double> MidpointErrors(const LookupTable& table,
                                   const std::function<void(double, double*)>& exact, double skip,
                                   double floor) {
  const auto columns = static_cast<std::size_t>(table.num_columns());
  std::vector<double> scale(columns, 0.0), want(columns), got(columns), error(columns, 0.0);
  for (std::size_t r = 0; r < table.num_rows(); ++r) {
    exact(table.x_min() + table.dx() * static_cast<double>(r), want.data());
    for (std::size_t c = 0; c < columns; ++c) scale[c] = std::max(scale[c], std::abs(want[c]));
  }
  for (std::size_t r = 0; r + 1 < table.num_rows(); ++r) {
    const double x = table.x_min() + table.dx() * (static_cast<double>(r) + 0.5);
    if (std::abs(x - skip) < table.dx()) continue;
    exact(x, want.data());
    table.InterpolateAll(x, got.data());
    for (std::size_t c = 0; c < columns; ++c)
      error[c] = std::max(
          error[c], std::abs(got[c] - want[c]) / std::max(std::abs(want[c]), floor * scale[c]));
  }
  return error;
}

// The lookup tables (0.05 mV steps, linear interpolation) against exact evaluation. Measured
// largest errors: voltage terms 2.1e-5 relative (the squared h∞ near −46 mV), IK1
// rectification 4.5e-5 relative (near V = EK); Rush–Larsen factors e^(−dt/τ) at dt = 0.01 ms
// 3.6e-6 absolute (m gate; what matters, since the gate error is |x − x∞| times it). They scale
// with the step squared (8.4e-5 for the voltage terms at 0.1 mV). Excluded: the interval around −40
// mV, where the model's own h and j rates jump (piecewise definitions) and the table replaces the
// jump by a 0.05 mV ramp. Then the effect on a whole action potential.
TEST(TenTusscherPanfilov2006, LookupTableErrorIsSmall) {
  TenTusscherPanfilov2006 model;
  const LookupTable* voltage = model.voltage_table();
  ASSERT_NE(voltage, nullptr);
  EXPECT_EQ(voltage->num_columns(), TenTusscherPanfilov2006::kNumVoltageTerms);
  EXPECT_DOUBLE_EQ(voltage->x_min(), -150.0);
  EXPECT_NEAR(voltage->x_max(), 150.0, 1e-9);
  auto terms = [&](double v, double* row) { model.CalcVoltageTerms(v, row); };
  for (double e : MidpointErrors(*voltage, terms, -40.0, 1e-3)) EXPECT_LT(e, 5e-5);

  const double dt = 0.01;
  const LookupTable* decay = model.DecayTable(dt);
  ASSERT_NE(decay, nullptr);
  EXPECT_TRUE(decay->SameGrid(*voltage));
  EXPECT_EQ(model.DecayTable(dt), decay);  // cached
  auto factors = [&](double v, double* row) {
    model.CalcGateRates(v, row);
    for (int k = 0; k < TenTusscherPanfilov2006::kNumVoltageGates; ++k)
      row[k] = std::exp(-dt * row[k]);
  };
  for (double e : MidpointErrors(*decay, factors, -40.0, 1.0)) EXPECT_LT(e, 1e-5);

  const std::vector<double> k1 = MidpointErrors(
      *model.k1_table(),
      [](double dk, double* row) { row[0] = TenTusscherPanfilov2006::CalcK1Rectification(dk); },
      1e9, 1e-3);
  EXPECT_LT(k1[0], 1e-4);

  // An action potential with and without the tables: APD within 0.01 %, trace RMS 0.01 mV
  // (measured 3e-5 % and 5e-5 mV).
  auto exact_model =
      MakeCellModel(R"({"model": "TenTusscherPanfilov2006", "lookup_tables": false})");
  const SingleCellResult with = Pace(model, 0.01, 1, 10, 400.0);
  const SingleCellResult without = Pace(*exact_model, 0.01, 1, 10, 400.0);
  EXPECT_NEAR(with.beats[0].apd / without.beats[0].apd, 1.0, 1e-4);
  EXPECT_LT(RmsDifference(with.voltage, without.voltage), 0.01);
}

TEST(TenTusscherPanfilov2006, KeepsEightRushLarsenTablesThenEvaluatesExactly) {
  TenTusscherPanfilov2006 model;
  for (int k = 1; k <= 8; ++k) EXPECT_NE(model.DecayTable(0.001 * k), nullptr) << k;
  EXPECT_EQ(model.DecayTable(0.5), nullptr);
  EXPECT_NE(model.DecayTable(0.004), nullptr);  // still cached
  // A ninth dt still steps, with exactly evaluated factors: same result as without tables up
  // to the table error of the other terms.
  auto exact = MakeCellModel(R"({"model": "TenTusscherPanfilov2006", "lookup_tables": false})");
  CellStates a(model, 1), b(*exact, 1);
  const double stim[1] = {52.0};
  for (int n = 0; n < 100; ++n) {
    model.Step(a.view(), 0, 1, 0.02, stim);
    exact->Step(b.view(), 0, 1, 0.02, stim);
  }
  EXPECT_NEAR(a.Get(0, 0), b.Get(0, 0), 1e-3);
}

TEST(TenTusscherPanfilov2006, VoltagesOutsideTheTableReadItsEnds) {
  TenTusscherPanfilov2006 model;
  std::vector<double> low(TenTusscherPanfilov2006::kNumVoltageTerms), at(low.size());
  model.voltage_table()->InterpolateAll(-400.0, low.data());
  model.CalcVoltageTerms(-150.0, at.data());
  for (std::size_t c = 0; c < low.size(); ++c) EXPECT_DOUBLE_EQ(low[c], at[c]);
  model.voltage_table()->InterpolateAll(std::nan(""), low.data());
  for (std::size_t c = 0; c < low.size(); ++c) EXPECT_DOUBLE_EQ(low[c], at[c]);
  // A huge depolarisation does not break the step (values stay finite).
  CellStates states(model, 1);
  states.Set(0, 0, 200.0);
  model.Step(states.view(), 0, 1, 0.01);
  for (int k = 0; k < model.num_states(); ++k) EXPECT_TRUE(std::isfinite(states.Get(0, k))) << k;
}

TEST(TenTusscherPanfilov2006, StimulusCurrentIsCarriedByPotassium) {
  // With a stimulus I the cell loses K⁺ at I Cm/(Vc F) on top of the ionic fluxes.
  TenTusscherPanfilov2006 model;
  CellStates with(model, 1), without(model, 1);
  const double stim[1] = {10.0};
  model.Step(with.view(), 0, 1, 0.01, stim);
  model.Step(without.view(), 0, 1, 0.01);
  const double cm_vc_f = 0.185 / (0.016404 * 96485.3415);
  const int ki = model.FindState("Ki");
  EXPECT_NEAR(with.Get(0, ki) - without.Get(0, ki), 0.01 * 10.0 * cm_vc_f, 1e-13);
  EXPECT_NEAR(with.Get(0, 0) - without.Get(0, 0), 0.01 * 10.0, 1e-12);
}

}  // namespace
}  // namespace gipsi
