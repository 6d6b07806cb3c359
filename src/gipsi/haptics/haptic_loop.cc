#include "gipsi/haptics/haptic_loop.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "gipsi/base/error.h"

namespace gipsi {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

HapticLoop::HapticLoop(HapticRenderer& tick, double rate, std::size_t max_records)
    : tick_(tick), period_(1.0 / rate) {
  GIPSI_CHECK(rate > 0 && rate <= 10000, "haptic rate {} Hz out of (0, 10000]", rate);
  periods_.resize(max_records);
}

HapticLoop::~HapticLoop() { Stop(); }

void HapticLoop::Start() {
  GIPSI_CHECK(!thread_.joinable(), "HapticLoop started twice");
  stop_.store(false);
  thread_ = std::thread([this] { Run(); });
}

void HapticLoop::Stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

void HapticLoop::Run() {
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_));
  const auto start = Clock::now();
  auto previous = start;
  auto next = start + period;
  while (!stop_.load(std::memory_order_relaxed)) {
    std::this_thread::sleep_until(next);
    const auto now = Clock::now();
    if (ticks_ > 0 && recorded_ < periods_.size())
      periods_[recorded_++] = std::chrono::duration<double>(now - previous).count();
    previous = now;
    const double t = std::chrono::duration<double>(now - start).count();
    tick_.Run(t, period_);
    cost_ += std::chrono::duration<double>(Clock::now() - now).count();
    ++ticks_;
    next += period;
    if (now > next) next = now + period;  // overrun: resynchronise, do not burst
  }
}

HapticLoopStats HapticLoop::Stats() const {
  HapticLoopStats s;
  s.ticks = ticks_;
  s.target_period = period_;
  s.mean_tick_cost = ticks_ > 0 ? cost_ / static_cast<double>(ticks_) : 0;
  if (recorded_ == 0) return s;
  std::vector<double> p(periods_.begin(),
                        periods_.begin() + static_cast<std::ptrdiff_t>(recorded_));
  std::vector<double> e(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) e[i] = std::abs(p[i] - period_);
  std::sort(p.begin(), p.end());
  std::sort(e.begin(), e.end());
  auto at = [](const std::vector<double>& v, double q) {
    return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
  };
  s.p50 = at(p, 0.5);
  s.p99 = at(p, 0.99);
  s.p999 = at(p, 0.999);
  s.max = p.back();
  s.error_p50 = at(e, 0.5);
  s.error_p99 = at(e, 0.99);
  s.error_p999 = at(e, 0.999);
  return s;
}

}  // namespace gipsi
