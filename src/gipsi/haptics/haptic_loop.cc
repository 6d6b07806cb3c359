#include "gipsi/haptics/haptic_loop.h"

#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"

namespace gipsi {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

HapticLoop::HapticLoop(HapticRenderer& tick, double rate, std::size_t max_records,
                       const HapticRealtime& realtime)
    : tick_(tick), period_(1.0 / rate), realtime_(realtime) {
  GIPSI_CHECK(rate > 0 && rate <= 10000, "haptic rate {} Hz out of (0, 10000]", rate);
  GIPSI_CHECK(!realtime.fifo || (realtime.priority >= 1 && realtime.priority <= 99),
              "SCHED_FIFO priority {} out of 1-99", realtime.priority);
  GIPSI_CHECK(realtime.spin >= 0 && realtime.spin < period_, "spin {} s outside [0, {}) s",
              realtime.spin, period_);
  periods_.resize(max_records);
}

HapticLoop::~HapticLoop() { Stop(); }

void HapticLoop::Start() {
  GIPSI_CHECK(!thread_.joinable(), "HapticLoop started twice");
  stop_.store(false);
  ready_.store(false);
  start_ = Clock::now();
  thread_ = std::thread([this] { Run(); });
  while (!ready_.load()) std::this_thread::yield();
  if (fifo_error_ != 0)
    Log().warn(
        "haptic loop: SCHED_FIFO (priority {}) not permitted ({}); running at normal "
        "priority",
        realtime_.priority, std::strerror(fifo_error_));
  if (pin_error_ != 0)
    Log().warn("haptic loop: cannot pin the thread to CPU {} ({}); running unpinned", realtime_.cpu,
               std::strerror(pin_error_));
}

void HapticLoop::ApplyScheduling() {
  // Wake-ups within ~1 µs of the deadline instead of up to 50 µs late (SCHED_FIFO threads have
  // no slack anyway). Per thread; cannot fail for a valid value.
  (void)prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  if (realtime_.fifo) {
    sched_param param{};
    param.sched_priority = realtime_.priority;
    fifo_error_ = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  }
  if (realtime_.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    if (realtime_.cpu < CPU_SETSIZE) CPU_SET(static_cast<std::size_t>(realtime_.cpu), &set);
    pin_error_ = realtime_.cpu < CPU_SETSIZE
                     ? pthread_setaffinity_np(pthread_self(), sizeof(set), &set)
                     : EINVAL;
  }
}

double HapticLoop::Elapsed() const {
  if (start_ == Clock::time_point{}) return 0;
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

void HapticLoop::Stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

void HapticLoop::Run() {
  ApplyScheduling();
  ready_.store(true);
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_));
  const auto start = start_;
  auto previous = Clock::now();
  auto next = previous + period;
  const auto spin =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(realtime_.spin));
  while (!stop_.load(std::memory_order_relaxed)) {
    if (spin.count() > 0) {
      std::this_thread::sleep_until(next - spin);
      while (Clock::now() < next) {  // spin out the rest: no timer wake-up latency
      }
    } else {
      std::this_thread::sleep_until(next);
    }
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
  s.fifo = realtime_.fifo && fifo_error_ == 0;
  s.pinned = realtime_.cpu >= 0 && pin_error_ == 0;
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
