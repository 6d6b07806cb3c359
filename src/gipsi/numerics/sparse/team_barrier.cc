#include "gipsi/numerics/sparse/team_barrier.h"

#include <sched.h>

#include <algorithm>
#include <thread>

namespace gipsi {

int AvailableCores() {
  static const int cores = [] {
    cpu_set_t set;
    CPU_ZERO(&set);
    if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
    return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  }();
  return cores;
}

}  // namespace gipsi
