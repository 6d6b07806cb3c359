#include "gipsi/haptics/force_safety.h"

#include <algorithm>
#include <cmath>

namespace gipsi {

Vec3 ForceSafety::Filter(const Vec3& desired, double dt, double model_age,
                         bool connected) noexcept {
  if (!(dt > 0)) return last_;
  const bool healthy = connected && model_age <= params_.stale_after;
  const double step = params_.fade_time > 0 ? dt / params_.fade_time : 1.0;
  gain_ = healthy ? std::min(1.0, gain_ + step) : std::max(0.0, gain_ - step);
  Vec3 f = desired.allFinite() ? Vec3(gain_ * desired) : Vec3::Zero();
  bool limited = false;
  const double norm = f.norm();
  if (norm > params_.max_force) {
    f *= params_.max_force / norm;
    limited = true;
  }
  const Vec3 change = f - last_;
  const double max_change = params_.max_rate * dt;
  const double change_norm = change.norm();
  if (change_norm > max_change) {
    f = last_ + (max_change / change_norm) * change;
    limited = true;
  }
  limited_ += limited ? 1 : 0;
  last_ = f;
  return f;
}

}  // namespace gipsi
