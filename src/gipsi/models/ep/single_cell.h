#pragma once
/// @file
/// Single-cell pacing: one cell of a CellModel stimulated at a basic cycle length, its voltage
/// recorded, and the usual action-potential biomarkers measured per beat (peak, resting
/// potential, maximal upstroke velocity, activation time, APD at X % repolarisation).

#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/models/ep/cell_model.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// How to pace the cell. Plain configuration; copyable.
///
/// Beat k starts at step round(k bcl/dt) (time k·bcl up to rounding) and the stimulus is on for
/// the first round(stim_duration/dt) steps of each beat (at least one step if stim_duration > 0),
/// so the injected charge is stim_amplitude · stim_duration up to one step.
struct PacingProtocol {
  double bcl = 1000.0;                ///< basic cycle length [ms], > 0
  std::int64_t beats = 1;             ///< number of beats (stimuli), ≥ 1
  double dt = 0.01;                   ///< time step [ms], in (0, bcl]
  double stim_amplitude = 52.0;       ///< stimulus [µA/µF]; positive depolarises
  double stim_duration = 1.0;         ///< [ms], in [0, bcl]
  std::int64_t record_every = 1;      ///< keep V every k-th step in the result (0: keep none)
  double apd_percent = 90.0;          ///< APD measured at this % repolarisation, in (0, 100)
  double activation_threshold = 0.0;  ///< activation = upward crossing of this V [mV]
};

/// Biomarkers of one beat; NaN where undefined (no activation, no repolarisation within the
/// beat). Copyable.
struct BeatMetrics {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  std::int64_t beat = 0;         ///< 0-based
  double start = 0;              ///< time of the beat's stimulus onset [ms]
  double rest = kNaN;            ///< minimum V from the beat's start to activation [mV]
  double peak = kNaN;            ///< maximum V after activation [mV]
  double dvdt_max = kNaN;        ///< maximum dV/dt over the beat (finite differences) [mV/ms]
  double activation = kNaN;      ///< first upward crossing of the threshold, interpolated [ms]
  double repolarisation = kNaN;  ///< first downward crossing of peak − X% (peak − rest) [ms]
  double apd = kNaN;             ///< repolarisation − activation [ms]
  [[nodiscard]] bool activated() const { return !std::isnan(activation); }
};

/// Everything a pacing run produced. Copyable and movable.
struct SingleCellResult {
  std::vector<double> time;         ///< times of the recorded samples [ms] (every k-th step)
  std::vector<double> voltage;      ///< V at those times [mV]
  std::vector<BeatMetrics> beats;   ///< one per beat
  std::vector<double> final_state;  ///< the state after the last step
};

/// Receives a sample: time [ms] and the full state (the model's order).
using CellSampleFn = std::function<void(double t, std::span<const double> state)>;

/// Paces one cell of `model` from `initial` (the model's resting state when empty) following
/// `protocol`. Biomarkers use every step, whatever `record_every`. `on_sample` (optional) is
/// called every `sample_every` steps (if > 0), including t = 0 and the final time. Throws
/// InputError for an invalid protocol or an initial state of the wrong size.
SingleCellResult PaceSingleCell(const CellModel& model, const PacingProtocol& protocol,
                                std::span<const double> initial = {},
                                const CellSampleFn& on_sample = {}, std::int64_t sample_every = 0);

/// The CSV header of a state trace: "t_ms" then each state as name_unit ("V_mV", "Cai_mM"),
/// dimensionless states by name alone ("m").
std::string CellTraceCsvHeader(const CellModel& model);

}  // namespace gipsi
GIPSI_EXPORT_END
