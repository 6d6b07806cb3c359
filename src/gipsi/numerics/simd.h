#pragma once
/// @file
/// Which vector instructions the hand-vectorised numerical kernels use.
///
/// The release build targets plain x86-64 (SSE2), so one binary runs on any 64-bit x86. The few
/// kernels that dominate a solve (the node-block product of CG, numerics/sparse/node_block_copy.h)
/// have a second, AVX version that the program selects when the processor and the operating
/// system support AVX. The AVX versions perform the same operations in the same order as the
/// generic ones, without fused multiply-adds, so both give the same bits: the choice changes
/// speed, never results. Tests check this by forcing the generic kernels.

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

enum class SimdKernels {
  kGeneric,  ///< SSE2, what every x86-64 (and any other) processor runs
  kAvx,      ///< 256-bit AVX (x86-64 with AVX, OS support checked), no FMA
};

/// The kernels in use: the best the machine supports, unless limited by LimitSimdKernels or
/// by the environment variable GIPSI_SIMD=generic (read once, at the first call).
[[nodiscard]] SimdKernels ActiveSimdKernels();
/// Uses at most `limit` (e.g. kGeneric to compare bits in tests, or to rule the AVX kernels
/// out when debugging); returns the previous limit. Not meant to change while kernels run.
SimdKernels LimitSimdKernels(SimdKernels limit);
/// "avx" or "generic", for logs and `gipsi --version`.
[[nodiscard]] const char* SimdKernelsName(SimdKernels kernels);

}  // namespace gipsi
GIPSI_EXPORT_END
