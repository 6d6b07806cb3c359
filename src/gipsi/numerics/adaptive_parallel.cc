#include "gipsi/numerics/adaptive_parallel.h"

#include <algorithm>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace gipsi {

int MaxTeamThreads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

bool AdaptiveParallel::Next() {
  bool parallel = prefer_parallel_;
  const double other = average_[parallel ? 0 : 1];
  ++calls_since_probe_;
  const bool due =
      other < 0 ? calls_since_probe_ >= kFirstProbe : time_since_probe_ >= kProbeRatio * other;
  if (due) {  // now and then, the other way once
    parallel = !parallel;
    calls_since_probe_ = 0;
    time_since_probe_ = 0;
  }
  ++calls_[parallel ? 1 : 0];
  return parallel;
}

void AdaptiveParallel::Record(bool parallel, double seconds) {
  const int way = parallel ? 1 : 0;
  const bool probe = parallel != prefer_parallel_;
  // The preferred way runs every call: a moving average over about four calls follows a
  // change of load within a few calls. A probe replaces the other way's figure, which is
  // stale.
  average_[way] = probe || average_[way] < 0 ? seconds : 0.75 * average_[way] + 0.25 * seconds;
  if (!probe) time_since_probe_ += seconds;
  if (average_[0] < 0 || average_[1] < 0) return;
  const bool was = prefer_parallel_;
  prefer_parallel_ = average_[1] < average_[0];
  if (prefer_parallel_ != was) {  // the way just left is measured: its probe comes in time
    calls_since_probe_ = 0;
    time_since_probe_ = 0;
  }
}

bool AdaptiveParallel::Begin(bool eligible) {
  timing_ = eligible;
  if (!eligible) return false;
  running_parallel_ = Next();
  start_ = Clock::now();
  return running_parallel_;
}

void AdaptiveParallel::End(double units) {
  if (!timing_) return;
  timing_ = false;
  Record(running_parallel_,
         std::chrono::duration<double>(Clock::now() - start_).count() / std::max(units, 1e-300));
}

}  // namespace gipsi
