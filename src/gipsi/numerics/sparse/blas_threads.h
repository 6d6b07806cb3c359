#pragma once
/// @file
/// `UseSingleThreadedBlas`: makes the BLAS under CHOLMOD run on the calling thread, whichever
/// BLAS the system provides, without changing the system's choice.
///
/// CHOLMOD makes many small BLAS calls per factorisation. A threaded BLAS wakes its own team for
/// each of them: Debian's pthread OpenBLAS spins against GiPSi's OpenMP threads and its OpenMP
/// build sleeps and wakes, both measured 50x slower on the heart's tangents than a serial BLAS.
/// Debian selects the BLAS through the libblas.so.3 alternative, which belongs to the user's
/// machine (NumPy, R and Octave use it too), so GiPSi leaves it alone and instead asks the loaded
/// BLAS, at run time, for one thread: OpenBLAS (`openblas_set_num_threads`) and BLIS
/// (`bli_thread_set_num_threads`) are recognised; the reference BLAS and serial builds need
/// nothing and are left as they are.

#include <functional>
#include <string_view>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// What `UseSingleThreadedBlas` did.
struct BlasThreadsResult {
  bool openblas = false;  ///< `openblas_set_num_threads(1)` was called
  bool blis = false;      ///< `bli_thread_set_num_threads(1)` was called
};

/// Looks a C symbol up in the running process (default: `dlsym(RTLD_DEFAULT, name)`); returns
/// null when no loaded library defines it. Tests pass their own.
using SymbolLookup = std::function<void*(std::string_view name)>;

/// Asks every recognised BLAS found by `lookup` for one thread. Idempotent and cheap.
BlasThreadsResult UseSingleThreadedBlas(const SymbolLookup& lookup);

/// The same with the process's own symbols, once per process (thread-safe); CHOLMOD solvers call
/// it before their first factorisation.
void UseSingleThreadedBlasOnce();

}  // namespace gipsi
GIPSI_EXPORT_END
