#pragma once
/// @file
/// `SerialOpenMp`: runs a library call's OpenMP regions on the calling thread alone.
///
/// Debian's CHOLMOD (SuiteSparse 5) opens OpenMP regions of a fixed four threads (its
/// compile-time CHOLMOD_OMP_NUM_THREADS, which ignores OMP_NUM_THREADS) to clear and copy
/// supernodes during a numeric factorisation. On two cores that team spends more time in futex
/// waits than it saves: the heart demo's 168 factorisations of a 1,326-unknown tangent made
/// 120,000 futex calls and took twice the wall time of the same factorisations run serially.
/// Setting max-active-levels to 0 makes every region opened inside the guard inactive (one
/// thread); the previous value is restored when the guard ends. GiPSi's own OpenMP regions run
/// on the same thread before and after, never concurrently with the guarded call.

#ifdef _OPENMP
#include <omp.h>

#include "gipsi/base/export.h"
#endif

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Scope guard; not copyable.
class SerialOpenMp {
 public:
  SerialOpenMp() {
#ifdef _OPENMP
    levels_ = omp_get_max_active_levels();
    omp_set_max_active_levels(0);
#endif
  }
  ~SerialOpenMp() {
#ifdef _OPENMP
    omp_set_max_active_levels(levels_);
#endif
  }
  SerialOpenMp(const SerialOpenMp&) = delete;
  SerialOpenMp& operator=(const SerialOpenMp&) = delete;

 private:
  int levels_ = 1;
};

}  // namespace gipsi
GIPSI_EXPORT_END
