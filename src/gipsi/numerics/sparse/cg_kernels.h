#pragma once
/// @file
/// The vector sweeps of the fused Jacobi-CG (pcg.cc, IterateFused) and the finiteness check of
/// the matrices the solvers take, with an AVX version chosen at run time (numerics/simd.h). Both
/// versions add the sums in four interleaved chains (entry i of a range in chain i mod 4, the
/// chains combined as (c0 + c1) + (c2 + c3)), so they give the same bits; only the speed depends on
/// the processor.

#include <cstddef>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Partial sums of one CG update sweep.
struct CgUpdateSums {
  double rr = 0.0;  ///< (r, r) over the rows
  double rz = 0.0;  ///< (r, z) over the rows
};

/// For rows [begin, end): p ← z + βp, s ← w + βs, x += αp, r −= αs, z = d ∘ r (d: the inverse
/// diagonal), and the new (r, r) and (r, z) over those rows. The arrays must not overlap.
CgUpdateSums CgUpdateRows(double alpha, double beta, const double* d, const double* w, double* x,
                          double* r, double* z, double* p, double* s, int begin, int end);

/// (a, b) over rows [begin, end).
double DotRows(const double* a, const double* b, int begin, int end);

/// True if all n values are finite (no NaN, no infinity).
bool AllFiniteValues(const double* values, std::ptrdiff_t n);

}  // namespace gipsi
GIPSI_EXPORT_END
