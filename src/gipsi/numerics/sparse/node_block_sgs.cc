#include "gipsi/numerics/sparse/node_block_sgs.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>

#include "gipsi/base/error.h"
#include "gipsi/numerics/simd.h"
#include "gipsi/numerics/simd_v4.h"
#include "gipsi/numerics/sparse/vector_ops.h"

namespace gipsi {
namespace sgs_detail {

// What the kernels read and write: NodeBlockSgs's arrays.
struct Sweep {
  const int* forward_start;
  const int* forward_lower;
  const int* forward_column;
  const double* forward_values;
  const int* backward_start;
  const int* backward_column;
  const double* backward_values;
  const double* inverse;
  const double* block;  // D_I, column-major, 9 per node
  double* z;
  double* rd;  // R
  double* p;
  double* t;
  double* u;
  double* w;
};

}  // namespace sgs_detail
namespace {

using sgs_detail::Sweep;
using simd::Load;
using V4 = simd::V4d;

// The inverses' padding: the kernels load a 3×3's third column as four doubles.
constexpr std::size_t kPadding = 4;

// A node's three entries in lanes 0-2, lane 3 zero (reading a fourth would pass the end of the
// last node's vector).
GIPSI_SIMD_INLINE void Load3(V4& v, const double* p) { v = V4{p[0], p[1], p[2], 0.0}; }
GIPSI_SIMD_INLINE void Store3(double* p, const V4& v) {
  p[0] = v[0];
  p[1] = v[1];
  p[2] = v[2];
}

// sum += B x for a column-major 3×3 B at b: ((c0 x0 + c1 x1) + c2 x2), then added. Lane 3 reads
// the next stored value (finite: the matrix passed AllValuesFinite) and is never stored.
GIPSI_SIMD_INLINE void AddBlock(V4& sum, const double* b, double x0, double x1, double x2) {
  V4 c0, c1, c2;
  Load(c0, b);
  Load(c1, b + 3);
  Load(c2, b + 6);
  V4 t = c0 * V4{x0, x0, x0, x0};
  t += c1 * V4{x1, x1, x1, x1};
  t += c2 * V4{x2, x2, x2, x2};
  sum += t;
}
GIPSI_SIMD_INLINE void AddBlock(V4& sum, const double* b, const double* x) {
  AddBlock(sum, b, x[0], x[1], x[2]);
}

// B y for the three lanes of y, summed as AddBlock does.
GIPSI_SIMD_INLINE void BlockTimes(V4& out, const double* b, const V4& y) {
  V4 c0, c1, c2;
  Load(c0, b);
  Load(c1, b + 3);
  Load(c2, b + 6);
  const double y0 = y[0], y1 = y[1], y2 = y[2];
  out = c0 * V4{y0, y0, y0, y0};
  out += c1 * V4{y1, y1, y1, y1};
  out += c2 * V4{y2, y2, y2, y2};
}

// (a, b) over lanes 0-2 of a running lane-wise sum.
GIPSI_SIMD_INLINE double Lanes3(const V4& sum) { return (sum[0] + sum[1]) + sum[2]; }

GIPSI_SIMD_INLINE double StartBody(const Sweep& s, const double* r, int begin, int end) {
  V4 zr = {0.0, 0.0, 0.0, 0.0};
  const V4 zero = zr;
  for (int node = begin; node < end; ++node) {
    V4 sum = zero;
    for (int m = s.forward_lower[node]; m < s.forward_start[node + 1]; ++m)
      AddBlock(sum, s.forward_values + 9 * std::ptrdiff_t{m}, s.z + s.forward_column[m]);
    V4 ri, zi, di;
    Load3(ri, r + 3 * node);
    const V4 y = ri - sum;
    BlockTimes(zi, s.inverse + 9 * std::ptrdiff_t{node}, y);
    BlockTimes(di, s.block + 9 * std::ptrdiff_t{node}, zi);
    Store3(s.z + 3 * node, zi);
    Store3(s.rd + 3 * node, di);
    Store3(s.p + 3 * node, zero);
    zr += zi * di;
  }
  return Lanes3(zr);
}

GIPSI_SIMD_INLINE void BackwardBody(const Sweep& s, double beta, int begin, int end) {
  const V4 b = {beta, beta, beta, beta};
  for (int node = end - 1; node >= begin; --node) {
    V4 pi, ri, ti;
    Load3(pi, s.p + 3 * node);
    Load3(ri, s.rd + 3 * node);
    pi = ri + b * pi;
    // The farthest node first: t of the node just solved (I + 1) enters last, so the products
    // that do not wait for it overlap the previous node's solve.
    V4 sum = {0.0, 0.0, 0.0, 0.0};
    for (int m = s.backward_start[node + 1]; m < s.backward_start[node]; ++m)
      AddBlock(sum, s.backward_values + 9 * std::ptrdiff_t{m}, s.t + s.backward_column[m]);
    const V4 y = pi - sum;
    BlockTimes(ti, s.inverse + 9 * std::ptrdiff_t{node}, y);
    Store3(s.p + 3 * node, pi);
    Store3(s.t + 3 * node, ti);
  }
}

GIPSI_SIMD_INLINE double ForwardBody(const Sweep& s, int begin, int end) {
  const V4 zero = {0.0, 0.0, 0.0, 0.0};
  V4 pw = zero;
  for (int node = begin; node < end; ++node) {
    V4 c = zero, lu = zero;  // C t and L u of the node's rows
    for (int m = s.forward_start[node]; m < s.forward_lower[node]; ++m)
      AddBlock(c, s.forward_values + 9 * std::ptrdiff_t{m}, s.t + s.forward_column[m]);
    // u of the node just solved (I − 1) enters last (J increasing).
    for (int m = s.forward_lower[node]; m < s.forward_start[node + 1]; ++m)
      AddBlock(lu, s.forward_values + 9 * std::ptrdiff_t{m}, s.u + s.forward_column[m]);
    V4 pi, ti, wi;
    Load3(pi, s.p + 3 * node);
    Load3(ti, s.t + 3 * node);
    const V4 y = (pi + c) - lu;
    BlockTimes(wi, s.inverse + 9 * std::ptrdiff_t{node}, y);
    Store3(s.w + 3 * node, wi);
    Store3(s.u + 3 * node, wi - ti);
    pw += pi * wi;
  }
  return Lanes3(pw);
}

// With kResidual, also r = (D + L) Z: the nodes before I in the domain already hold their new Z.
template <bool kResidual>
GIPSI_SIMD_INLINE SgsUpdateSums UpdateSweep(const Sweep& s, double alpha, double* x, int begin,
                                            int end) {
  const V4 a = {alpha, alpha, alpha, alpha};
  V4 rr = {0.0, 0.0, 0.0, 0.0}, zr = rr;
  for (int node = begin; node < end; ++node) {
    const int i = 3 * node;
    V4 xi, ti, zi, wi, di;
    Load3(xi, x + i);
    Load3(ti, s.t + i);
    Load3(zi, s.z + i);
    Load3(wi, s.w + i);
    xi += a * ti;
    zi -= a * wi;
    BlockTimes(di, s.block + 9 * std::ptrdiff_t{node}, zi);
    Store3(x + i, xi);
    Store3(s.z + i, zi);
    Store3(s.rd + i, di);
    zr += zi * di;
    if constexpr (kResidual) {
      V4 ri = di;
      for (int m = s.forward_lower[node]; m < s.forward_start[node + 1]; ++m)
        AddBlock(ri, s.forward_values + 9 * std::ptrdiff_t{m}, s.z + s.forward_column[m]);
      rr += ri * ri;
    }
  }
  return {Lanes3(rr), Lanes3(zr)};
}
GIPSI_SIMD_INLINE SgsUpdateSums UpdateBody(const Sweep& s, double alpha, double* x, int begin,
                                           int end) {
  return UpdateSweep<false>(s, alpha, x, begin, end);
}
GIPSI_SIMD_INLINE SgsUpdateSums UpdateResidualBody(const Sweep& s, double alpha, double* x,
                                                   int begin, int end) {
  return UpdateSweep<true>(s, alpha, x, begin, end);
}

// y = A x for nodes [begin, end): D_I x_I, then the forward blocks, then the backward ones.
GIPSI_SIMD_INLINE void MultiplyBody(const Sweep& s, const double* x, double* y, int begin,
                                    int end) {
  for (int node = begin; node < end; ++node) {
    V4 sum = {0.0, 0.0, 0.0, 0.0};
    AddBlock(sum, s.block + 9 * std::ptrdiff_t{node}, x + 3 * node);
    for (int m = s.forward_start[node]; m < s.forward_start[node + 1]; ++m)
      AddBlock(sum, s.forward_values + 9 * std::ptrdiff_t{m}, x + s.forward_column[m]);
    for (int m = s.backward_start[node + 1]; m < s.backward_start[node]; ++m)
      AddBlock(sum, s.backward_values + 9 * std::ptrdiff_t{m}, x + s.backward_column[m]);
    Store3(y + 3 * node, sum);
  }
}

// One generic and one AVX copy of each kernel (the same operations: the same bits).
#if defined(__x86_64__)
#define GIPSI_SGS_AVX(Ret, Name, Params, Args) \
  __attribute__((target("avx"))) Ret Name##Avx Params { return Name##Body Args; }
#else
#define GIPSI_SGS_AVX(Ret, Name, Params, Args)
#endif
#define GIPSI_SGS_COPIES(Ret, Name, Params, Args)      \
  Ret Name##Generic Params { return Name##Body Args; } \
  GIPSI_SGS_AVX(Ret, Name, Params, Args)
GIPSI_SGS_COPIES(double, Start, (const Sweep& s, const double* r, int begin, int end),
                 (s, r, begin, end))
GIPSI_SGS_COPIES(void, Backward, (const Sweep& s, double beta, int begin, int end),
                 (s, beta, begin, end))
GIPSI_SGS_COPIES(double, Forward, (const Sweep& s, int begin, int end), (s, begin, end))
GIPSI_SGS_COPIES(void, Multiply, (const Sweep& s, const double* x, double* y, int begin, int end),
                 (s, x, y, begin, end))
GIPSI_SGS_COPIES(SgsUpdateSums, Update,
                 (const Sweep& s, double alpha, double* x, int begin, int end),
                 (s, alpha, x, begin, end))
GIPSI_SGS_COPIES(SgsUpdateSums, UpdateResidual,
                 (const Sweep& s, double alpha, double* x, int begin, int end),
                 (s, alpha, x, begin, end))
#undef GIPSI_SGS_COPIES
#undef GIPSI_SGS_AVX

bool UseAvx() {
#if defined(__x86_64__)
  return ActiveSimdKernels() == SimdKernels::kAvx;
#else
  return false;
#endif
}

// Inverse of the symmetric 3×3 `d` (column-major, its lower triangle read) through its Cholesky
// factor L (D = L Lᵀ, D⁻¹ = L⁻ᵀ L⁻¹), into `inverse` (column-major); false unless every pivot
// is positive and finite.
bool InvertSpd3(const double* d, double* inverse) {
  const double l00 = std::sqrt(d[0]);
  if (!(l00 > 0.0) || !std::isfinite(l00)) return false;
  const double l10 = d[1] / l00, l20 = d[2] / l00;
  const double p11 = d[4] - l10 * l10;
  if (!(p11 > 0.0)) return false;
  const double l11 = std::sqrt(p11);
  const double l21 = (d[5] - l20 * l10) / l11;
  const double p22 = d[8] - l20 * l20 - l21 * l21;
  if (!(p22 > 0.0) || !std::isfinite(p22)) return false;
  const double l22 = std::sqrt(p22);
  // M = L⁻¹ (lower triangular), then D⁻¹ = Mᵀ M.
  const double m00 = 1.0 / l00, m11 = 1.0 / l11, m22 = 1.0 / l22;
  const double m10 = -l10 * m00 * m11;
  const double m21 = -l21 * m11 * m22;
  const double m20 = -(l20 * m00 + l21 * m10) * m22;
  const double i00 = m00 * m00 + m10 * m10 + m20 * m20;
  const double i10 = m11 * m10 + m21 * m20, i20 = m22 * m20;
  const double i11 = m11 * m11 + m21 * m21, i21 = m22 * m21, i22 = m22 * m22;
  const double out[9] = {i00, i10, i20, i10, i11, i21, i20, i21, i22};
  std::copy(out, out + 9, inverse);
  return std::all_of(out, out + 9, [](double value) { return std::isfinite(value); });
}

}  // namespace

void NodeBlockSgs::AssignPattern(const SparseMatrix& A, int domains) {
  GIPSI_CHECK(HasNodeBlockPattern(A), "NodeBlockSgs: the matrix is not made of 3x3 node blocks");
  GIPSI_CHECK(domains >= 1, "NodeBlockSgs: {} domains", domains);
  const int n = static_cast<int>(A.cols() / 3);
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  auto count = [&](int node) { return (outer[3 * node + 1] - outer[3 * node]) / 3; };
  // Domains of about equal block counts: the first node whose blocks start at k/parts of them.
  const int parts = std::max(1, std::min(domains, n));
  domain_start_.assign(static_cast<std::size_t>(parts) + 1, n);
  domain_start_[0] = 0;
  for (int k = 1; k < parts; ++k) {
    const std::int64_t goal = std::int64_t{outer[3 * n] / 9} * k / parts;
    int node = domain_start_[static_cast<std::size_t>(k) - 1];
    while (node < n && outer[3 * node] / 9 < goal) ++node;
    domain_start_[static_cast<std::size_t>(k)] = node;
  }
  for (std::vector<int>* v : {&lower_, &diagonal_, &upper_end_, &source_, &forward_lower_})
    v->resize(static_cast<std::size_t>(n));
  forward_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  backward_start_.assign(static_cast<std::size_t>(n) + 1, 0);
  for (int d = 0; d < parts; ++d) {
    const int first = domain_start(d), last = domain_start(d + 1);
    for (int node = first; node < last; ++node) {
      const auto i = static_cast<std::size_t>(node);
      source_[i] = outer[3 * node];
      // Block m's column is row inner[source + 3m] / 3: sorted, with the diagonal one
      // (HasNodeBlockPattern).
      const int blocks = count(node);
      auto first_at_least = [&](int row) {
        int m = 0;
        while (m < blocks && inner[source_[i] + 3 * m] < row) ++m;
        return m;
      };
      lower_[i] = first_at_least(3 * first);
      diagonal_[i] = first_at_least(3 * node);
      upper_end_[i] = first_at_least(3 * last);
      const int cross = lower_[i] + (blocks - upper_end_[i]);
      forward_lower_[i] = forward_start_[i] + cross;
      forward_start_[i + 1] = forward_lower_[i] + (diagonal_[i] - lower_[i]);
    }
  }
  // Backward blocks from node n − 1 down: node I's end is its start plus its U blocks.
  for (int node = n - 1; node >= 0; --node) {
    const auto i = static_cast<std::size_t>(node);
    backward_start_[i] = backward_start_[i + 1] + (upper_end_[i] - diagonal_[i] - 1);
  }
  forward_column_.assign(static_cast<std::size_t>(forward_start_[static_cast<std::size_t>(n)]), 0);
  backward_column_.assign(static_cast<std::size_t>(backward_start_[0]), 0);
  for (int node = 0; node < n; ++node) {
    const auto i = static_cast<std::size_t>(node);
    const int* rows = inner + source_[i];
    const int blocks = count(node);
    int f = forward_start_[i];
    for (int m = 0; m < lower_[i]; ++m)
      forward_column_[static_cast<std::size_t>(f++)] = rows[3 * m];
    for (int m = upper_end_[i]; m < blocks; ++m)
      forward_column_[static_cast<std::size_t>(f++)] = rows[3 * m];
    for (int m = lower_[i]; m < diagonal_[i]; ++m)
      forward_column_[static_cast<std::size_t>(f++)] = rows[3 * m];
    int b = backward_start_[i + 1];
    for (int m = upper_end_[i] - 1; m > diagonal_[i]; --m)
      backward_column_[static_cast<std::size_t>(b++)] = rows[3 * m];
  }
  forward_values_.assign(9 * forward_column_.size() + kPadding, 0.0);
  backward_values_.assign(9 * backward_column_.size() + kPadding, 0.0);
  inverse_.assign(9 * static_cast<std::size_t>(n) + kPadding, 0.0);
  block_.assign(9 * static_cast<std::size_t>(n) + kPadding, 0.0);
  for (std::vector<double>* v : {&z_, &r_, &p_, &t_, &u_, &w_})
    v->assign(3 * static_cast<std::size_t>(n), 0.0);
  nonzeros_ = A.nonZeros();
}

bool NodeBlockSgs::Factorize(const SparseMatrix& A, bool team) {
  const int n = nodes();
  GIPSI_CHECK(A.cols() == 3 * n && A.nonZeros() == nonzeros_,
              "NodeBlockSgs::Factorize: the matrix does not have the analysed pattern");
  const double* values = A.valuePtr();
  std::atomic<int> failed{0};
  ForRange(0, n, team && 3 * n >= kMinParallelLength, [&](int node) {
    const auto i = static_cast<std::size_t>(node);
    const int blocks = (A.outerIndexPtr()[3 * node + 1] - source_[i]) / 3;
    // Column 3I + a holds A(3J + i, 3I + a) = A(3I + a, 3J + i) (symmetry) at source + 3m + i
    // for the node's block m, the three columns one after the other.
    const double* column = values + source_[i];
    auto copy_block = [&](int m, double* out) {
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 3; ++k) out[3 * k + a] = column[3 * blocks * a + 3 * m + k];
    };
    double* f = forward_values_.data() + 9 * std::ptrdiff_t{forward_start_[i]};
    for (int m = 0; m < lower_[i]; ++m, f += 9) copy_block(m, f);
    for (int m = upper_end_[i]; m < blocks; ++m, f += 9) copy_block(m, f);
    for (int m = lower_[i]; m < diagonal_[i]; ++m, f += 9) copy_block(m, f);
    double* b = backward_values_.data() + 9 * std::ptrdiff_t{backward_start_[i + 1]};
    for (int m = upper_end_[i] - 1; m > diagonal_[i]; --m, b += 9) copy_block(m, b);
    double* d = block_.data() + 9 * std::ptrdiff_t{node};
    copy_block(diagonal_[i], d);
    if (!InvertSpd3(d, inverse_.data() + 9 * std::ptrdiff_t{node}))
      failed.fetch_add(1, std::memory_order_relaxed);
  });
  return failed.load() == 0;
}

Sweep NodeBlockSgs::MakeSweep() {
  return {forward_start_.data(),
          forward_lower_.data(),
          forward_column_.data(),
          forward_values_.data(),
          backward_start_.data(),
          backward_column_.data(),
          backward_values_.data(),
          inverse_.data(),
          block_.data(),
          z_.data(),
          r_.data(),
          p_.data(),
          t_.data(),
          u_.data(),
          w_.data()};
}

double NodeBlockSgs::Start(const double* r, int d) {
  const Sweep s = MakeSweep();
  const int begin = domain_start(d), end = domain_start(d + 1);
#if defined(__x86_64__)
  if (UseAvx()) return StartAvx(s, r, begin, end);
#endif
  return StartGeneric(s, r, begin, end);
}

void NodeBlockSgs::Backward(double beta, int d) {
  const Sweep s = MakeSweep();
  const int begin = domain_start(d), end = domain_start(d + 1);
#if defined(__x86_64__)
  if (UseAvx()) return BackwardAvx(s, beta, begin, end);
#endif
  BackwardGeneric(s, beta, begin, end);
}

double NodeBlockSgs::Forward(int d) {
  const Sweep s = MakeSweep();
  const int begin = domain_start(d), end = domain_start(d + 1);
#if defined(__x86_64__)
  if (UseAvx()) return ForwardAvx(s, begin, end);
#endif
  return ForwardGeneric(s, begin, end);
}

SgsUpdateSums NodeBlockSgs::Update(double alpha, double* x, bool residual, int d) {
  const Sweep s = MakeSweep();
  const int begin = domain_start(d), end = domain_start(d + 1);
#if defined(__x86_64__)
  if (UseAvx())
    return residual ? UpdateResidualAvx(s, alpha, x, begin, end)
                    : UpdateAvx(s, alpha, x, begin, end);
#endif
  return residual ? UpdateResidualGeneric(s, alpha, x, begin, end)
                  : UpdateGeneric(s, alpha, x, begin, end);
}

void NodeBlockSgs::Multiply(const VecX& x, VecX& y) {
  const int n = nodes();
  GIPSI_CHECK(x.size() == 3 * n && y.size() == 3 * n && x.data() != y.data(),
              "NodeBlockSgs::Multiply: sizes do not match or x and y alias");
  const Sweep s = MakeSweep();
  const bool avx = UseAvx();
  constexpr int kBatch = 64;
  ForRange(0, (n + kBatch - 1) / kBatch, 3 * n >= kMinParallelLength, [&](int b) {
    const int begin = b * kBatch, end = std::min((b + 1) * kBatch, n);
#if defined(__x86_64__)
    if (avx) return MultiplyAvx(s, x.data(), y.data(), begin, end);
#endif
    MultiplyGeneric(s, x.data(), y.data(), begin, end);
  });
}

}  // namespace gipsi
