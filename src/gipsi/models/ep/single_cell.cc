#include "gipsi/models/ep/single_cell.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {

namespace {

void CheckProtocol(const PacingProtocol& p) {
  auto fail = [](const char* field, const std::string& what) {
    ThrowInputError("", fmt::format("pacing protocol: {}", field), what);
  };
  if (!(p.bcl > 0) || !std::isfinite(p.bcl))
    fail("bcl", fmt::format("expected a positive cycle length [ms], got {}", p.bcl));
  if (p.beats < 1) fail("beats", fmt::format("expected at least one beat, got {}", p.beats));
  if (!(p.dt > 0) || !(p.dt <= p.bcl))
    fail("dt", fmt::format("expected a time step in (0, bcl = {}] ms, got {}", p.bcl, p.dt));
  if (!std::isfinite(p.stim_amplitude))
    fail("stim_amplitude", fmt::format("expected a finite number, got {}", p.stim_amplitude));
  if (!(p.stim_duration >= 0) || !(p.stim_duration <= p.bcl))
    fail("stim_duration",
         fmt::format("expected a duration in [0, bcl = {}] ms, got {}", p.bcl, p.stim_duration));
  if (p.record_every < 0)
    fail("record_every", fmt::format("expected a non-negative step count, got {}", p.record_every));
  if (!(p.apd_percent > 0 && p.apd_percent < 100))
    fail("apd_percent", fmt::format("expected a percentage in (0, 100), got {}", p.apd_percent));
  if (!std::isfinite(p.activation_threshold))
    fail("activation_threshold",
         fmt::format("expected a finite voltage, got {}", p.activation_threshold));
  if (static_cast<double>(p.beats) * p.bcl / p.dt > 1e11)
    fail("dt", "more than 1e11 steps: use a larger dt or fewer beats");
}

/// Per-beat biomarkers from the voltage at every step, online (no trace kept).
class BeatAnalyzer {
 public:
  BeatAnalyzer(double apd_percent, double threshold)
      : fraction_(apd_percent / 100.0), threshold_(threshold) {}

  /// Starts beat `index` at time `t` (finishing the previous one).
  void StartBeat(std::int64_t index, double t) {
    Finish();
    current_ = BeatMetrics{};
    current_.beat = index;
    current_.start = t;
    running_ = true;
    min_ = max_ = std::numeric_limits<double>::quiet_NaN();
  }

  /// The sample (t, v), following (t_prev, v_prev) if `has_prev`.
  void Add(double t, double v, bool has_prev, double t_prev, double v_prev) {
    BeatMetrics& b = current_;
    if (!(v >= min_)) min_ = v;  // also takes the first sample
    if (!(v <= max_)) max_ = v;
    if (has_prev) {
      const double slope = (v - v_prev) / (t - t_prev);
      if (!(slope <= b.dvdt_max)) b.dvdt_max = slope;
    }
    if (!b.activated()) {
      if (!(v >= b.rest)) b.rest = v;
      if (has_prev && v_prev < threshold_ && v >= threshold_) {
        b.activation = t_prev + (t - t_prev) * (threshold_ - v_prev) / (v - v_prev);
        b.peak = v;
      }
      return;
    }
    if (v > b.peak) b.peak = v;
    if (!std::isnan(b.repolarisation)) return;
    const double level = b.peak - fraction_ * (b.peak - b.rest);
    if (v_prev >= level && v < level) {
      b.repolarisation = t_prev + (t - t_prev) * (v_prev - level) / (v_prev - v);
      b.apd = b.repolarisation - b.activation;
    }
  }

  void Finish() {
    if (!running_) return;
    if (!current_.activated()) {
      current_.rest = min_;
      current_.peak = max_;
    }
    beats_.push_back(current_);
    running_ = false;
  }

  [[nodiscard]] std::vector<BeatMetrics> TakeBeats() {
    Finish();
    return std::move(beats_);
  }

 private:
  double fraction_, threshold_;
  BeatMetrics current_;
  bool running_ = false;
  double min_ = 0, max_ = 0;
  std::vector<BeatMetrics> beats_;
};

}  // namespace

SingleCellResult PaceSingleCell(const CellModel& model, const PacingProtocol& protocol,
                                std::span<const double> initial, const CellSampleFn& on_sample,
                                std::int64_t sample_every) {
  CheckProtocol(protocol);
  const auto num_states = static_cast<std::size_t>(model.num_states());
  if (!initial.empty() && initial.size() != num_states)
    ThrowInputError("", "initial state",
                    fmt::format("{} has {} state variables, got {} values", model.type_name(),
                                num_states, initial.size()));
  CellStates states(model, 1);
  if (!initial.empty()) states.SetNode(0, initial);
  model.Prepare(protocol.dt);
  const int v_index = model.v_index();
  const double dt = protocol.dt;
  const auto total_steps = static_cast<std::int64_t>(
      std::llround(static_cast<double>(protocol.beats) * protocol.bcl / dt));
  auto beat_start = [&](std::int64_t k) {
    return static_cast<std::int64_t>(std::llround(static_cast<double>(k) * protocol.bcl / dt));
  };
  std::int64_t stim_steps = std::llround(protocol.stim_duration / dt);
  if (protocol.stim_duration > 0 && stim_steps < 1) stim_steps = 1;

  SingleCellResult result;
  BeatAnalyzer analyzer(protocol.apd_percent, protocol.activation_threshold);
  std::vector<double> state(num_states);
  double stimulus[1] = {0.0};
  std::int64_t beat = 0, next_beat_step = beat_start(1), stim_end_step = stim_steps;
  analyzer.StartBeat(0, 0.0);
  double t_prev = 0, v_prev = 0;
  for (std::int64_t n = 0;; ++n) {
    const double t = static_cast<double>(n) * dt;
    const double v = states.Get(0, v_index);
    if (n == next_beat_step && n < total_steps) {
      ++beat;
      analyzer.StartBeat(beat, t);
      next_beat_step = beat_start(beat + 1);
      stim_end_step = n + stim_steps;
    }
    analyzer.Add(t, v, n > 0, t_prev, v_prev);
    t_prev = t;
    v_prev = v;
    if (protocol.record_every > 0 && n % protocol.record_every == 0) {
      result.time.push_back(t);
      result.voltage.push_back(v);
    }
    if (on_sample && sample_every > 0 && (n % sample_every == 0 || n == total_steps)) {
      for (std::size_t k = 0; k < num_states; ++k) state[k] = states.Get(0, static_cast<int>(k));
      on_sample(t, state);
    }
    if (n == total_steps) break;
    stimulus[0] = n < stim_end_step ? protocol.stim_amplitude : 0.0;
    model.Step(states.view(), 0, 1, dt, stimulus);
  }
  result.beats = analyzer.TakeBeats();
  result.final_state = states.Node(0);
  return result;
}

std::string CellTraceCsvHeader(const CellModel& model) {
  std::string header = "t_ms";
  for (const CellStateInfo& info : model.states()) {
    header += ',';
    header += info.name;
    if (!info.unit.empty() && info.unit != "1") header += "_" + info.unit;
  }
  return header;
}

}  // namespace gipsi
