#pragma once
/// @file
/// `ForceSafety`: the last stage before a haptic device. It clamps the force to the device's
/// limit, limits how fast the force may change, and fades the force smoothly to zero when the
/// local model is stale (the simulation stalled) or the device is disconnected (a watchdog);
/// when both recover, the force fades back in at the same rate. Allocation-free, noexcept.

#include <cstdint>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// What a ForceSafety carries from one tick to the next (a state value type,
/// gipsi/base/state_value.h).
struct ForceSafetyState {
  double gain = 1;           ///< watchdog gain in [0, 1]
  Vec3 last = Vec3::Zero();  ///< the last commanded force [N]
  std::int64_t limited = 0;  ///< ticks whose force was clamped or rate limited
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("gain", s.gain);
    v("last", s.last);
    v("limited", s.limited);
  }
};

/// Parameters. Plain struct with defaults.
struct ForceSafetyParams {
  double max_force = 3.0;     ///< N, magnitude limit
  double max_rate = 1000.0;   ///< N/s, limit on |Δf| / Δt
  double stale_after = 0.05;  ///< s: a local model older than this is stale
  double fade_time = 0.1;     ///< s, from full force to zero (and back)
};

/// Not thread-safe (one haptic loop owns it). Copyable and movable.
class ForceSafety {
 public:
  explicit ForceSafety(const ForceSafetyParams& params = {}) : params_(params) {}

  /// The force to command this tick [N], from the `desired` force, the tick length `dt` [s]
  /// (> 0), the age of the local model [s] and the device's connection. Order: fade (the
  /// watchdog gain moves linearly by dt / fade_time toward 0 when stale or disconnected, toward
  /// 1 otherwise), clamp to max_force, then rate limit against the previous output. Non-finite
  /// input counts as zero force.
  Vec3 Filter(const Vec3& desired, double dt, double model_age, bool connected) noexcept;

  /// Current watchdog gain in [0, 1].
  [[nodiscard]] double gain() const { return gain_; }
  [[nodiscard]] const Vec3& last_output() const { return last_; }
  [[nodiscard]] const ForceSafetyParams& params() const { return params_; }
  /// Number of ticks whose force was clamped or rate limited.
  [[nodiscard]] std::int64_t num_limited() const { return limited_; }
  /// Checkpoints and roll-back: the watchdog gain, the last output and the count.
  [[nodiscard]] ForceSafetyState state() const { return {gain_, last_, limited_}; }
  void set_state(const ForceSafetyState& s) {
    gain_ = s.gain;
    last_ = s.last;
    limited_ = s.limited;
  }

 private:
  ForceSafetyParams params_;
  double gain_ = 1;
  Vec3 last_ = Vec3::Zero();
  std::int64_t limited_ = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
