#include "gipsi/numerics/sparse/supernodal_solve.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/numerics/simd.h"
#include "gipsi/numerics/simd_v4.h"

namespace gipsi {
namespace {

/// Below this many rows one solve takes a few tens of microseconds, about what waking the
/// second thread costs: such factors are solved on the calling thread (same arithmetic).
constexpr int kParallelRows = 4000;

using simd::Load;
using simd::Store;
using V4 = simd::V4d;

// One supernode: its column-major block L (nsrow × nscol, the triangle on top) and a work
// vector w of nsrow entries holding (y of its columns, the values of its off-diagonal rows).

/// Forward: w[0, nscol) ← L₁₁⁻¹ w[0, nscol), and w[nscol, nsrow) −= L₂₁ w[0, nscol); one pass
/// through the block, four columns at a time (each row of w loaded and stored once per four
/// columns).
GIPSI_SIMD_INLINE void ForwardBody(const double* __restrict block, double* __restrict w, int nsrow,
                                   int nscol) {
  const std::ptrdiff_t ld = nsrow;
  int j = 0;
  for (; j + 4 <= nscol; j += 4) {
    const double* c0 = block + j * ld;
    const double* c1 = c0 + ld;
    const double* c2 = c1 + ld;
    const double* c3 = c2 + ld;
    // The 4 × 4 diagonal block.
    const double w0 = w[j] / c0[j];
    const double w1 = (w[j + 1] - w0 * c0[j + 1]) / c1[j + 1];
    const double w2 = (w[j + 2] - w0 * c0[j + 2] - w1 * c1[j + 2]) / c2[j + 2];
    const double w3 = (w[j + 3] - w0 * c0[j + 3] - w1 * c1[j + 3] - w2 * c2[j + 3]) / c3[j + 3];
    w[j] = w0;
    w[j + 1] = w1;
    w[j + 2] = w2;
    w[j + 3] = w3;
    const V4 f0 = {w0, w0, w0, w0}, f1 = {w1, w1, w1, w1}, f2 = {w2, w2, w2, w2},
             f3 = {w3, w3, w3, w3};
    int i = j + 4;
    for (; i + 4 <= nsrow; i += 4) {
      V4 wi, l0, l1, l2, l3;
      Load(wi, w + i);
      Load(l0, c0 + i);
      Load(l1, c1 + i);
      Load(l2, c2 + i);
      Load(l3, c3 + i);
      wi -= (f0 * l0 + f1 * l1) + (f2 * l2 + f3 * l3);
      Store(w + i, wi);
    }
    for (; i < nsrow; ++i) w[i] -= (w0 * c0[i] + w1 * c1[i]) + (w2 * c2[i] + w3 * c3[i]);
  }
  for (; j < nscol; ++j) {
    const double* column = block + j * ld;
    const double wj = w[j] / column[j];
    w[j] = wj;
    const V4 factor = {wj, wj, wj, wj};
    int i = j + 1;
    for (; i + 4 <= nsrow; i += 4) {
      V4 wi, li;
      Load(wi, w + i);
      Load(li, column + i);
      wi -= factor * li;
      Store(w + i, wi);
    }
    for (; i < nsrow; ++i) w[i] -= wj * column[i];
  }
}

/// Backward: w[0, nscol) ← L₁₁⁻ᵀ (w[0, nscol) − L₂₁ᵀ w[nscol, nsrow)), from the last column,
/// four columns at a time (their dot products with the solved rows below them share the loads
/// of w).
GIPSI_SIMD_INLINE void BackwardBody(const double* __restrict block, double* __restrict w, int nsrow,
                                    int nscol) {
  const std::ptrdiff_t ld = nsrow;
  int j = nscol;
  for (; j >= 4; j -= 4) {
    const int j0 = j - 4;
    const double* c0 = block + j0 * ld;
    const double* c1 = c0 + ld;
    const double* c2 = c1 + ld;
    const double* c3 = c2 + ld;
    V4 s0 = {0.0, 0.0, 0.0, 0.0}, s1 = s0, s2 = s0, s3 = s0;
    int i = j;
    for (; i + 4 <= nsrow; i += 4) {
      V4 wi, l0, l1, l2, l3;
      Load(wi, w + i);
      Load(l0, c0 + i);
      Load(l1, c1 + i);
      Load(l2, c2 + i);
      Load(l3, c3 + i);
      s0 += l0 * wi;
      s1 += l1 * wi;
      s2 += l2 * wi;
      s3 += l3 * wi;
    }
    double d0[4], d1[4], d2[4], d3[4];
    Store(d0, s0);
    Store(d1, s1);
    Store(d2, s2);
    Store(d3, s3);
    for (int c = 0; i < nsrow; ++i, ++c) {
      d0[c] += c0[i] * w[i];
      d1[c] += c1[i] * w[i];
      d2[c] += c2[i] * w[i];
      d3[c] += c3[i] * w[i];
    }
    // The 4 × 4 diagonal block, from its last column.
    const double w3 = (w[j0 + 3] - ((d3[0] + d3[1]) + (d3[2] + d3[3]))) / c3[j0 + 3];
    const double w2 =
        (w[j0 + 2] - ((d2[0] + d2[1]) + (d2[2] + d2[3])) - c2[j0 + 3] * w3) / c2[j0 + 2];
    const double w1 =
        (w[j0 + 1] - ((d1[0] + d1[1]) + (d1[2] + d1[3])) - c1[j0 + 3] * w3 - c1[j0 + 2] * w2) /
        c1[j0 + 1];
    const double w0 = (w[j0] - ((d0[0] + d0[1]) + (d0[2] + d0[3])) - c0[j0 + 3] * w3 -
                       c0[j0 + 2] * w2 - c0[j0 + 1] * w1) /
                      c0[j0];
    w[j0] = w0;
    w[j0 + 1] = w1;
    w[j0 + 2] = w2;
    w[j0 + 3] = w3;
  }
  for (--j; j >= 0; --j) {
    const double* column = block + j * ld;
    w[j] = (w[j] - simd::Dot(column, w, j + 1, nsrow)) / column[j];
  }
}

void ForwardGeneric(const double* block, double* w, int nsrow, int nscol) {
  ForwardBody(block, w, nsrow, nscol);
}
void BackwardGeneric(const double* block, double* w, int nsrow, int nscol) {
  BackwardBody(block, w, nsrow, nscol);
}
__attribute__((target("avx"))) void ForwardAvx(const double* block, double* w, int nsrow,
                                               int nscol) {
  ForwardBody(block, w, nsrow, nscol);
}
__attribute__((target("avx"))) void BackwardAvx(const double* block, double* w, int nsrow,
                                                int nscol) {
  BackwardBody(block, w, nsrow, nscol);
}

}  // namespace

void SupernodalSolve::Analyze(const SupernodalFactorView& f) {
  GIPSI_CHECK(f.n >= 0 && f.nsuper >= 0 && (f.nsuper == 0 || (f.super && f.pi && f.px && f.s_rows)),
              "SupernodalSolve: not a supernodal factor");
  n_ = f.n;
  nsuper_ = f.nsuper;
  const auto ns = static_cast<std::size_t>(nsuper_);
  auto at = [](int i) { return static_cast<std::size_t>(i); };
  // Each supernode's parent (the supernode of its first off-diagonal row), the entries of its
  // subtree (what the solves read), its first descendant and its children.
  std::vector<int> col_super(at(n_), -1);
  std::vector<int> parent(ns, -1), first(ns);
  std::vector<std::vector<int>> children(ns);
  std::vector<double> subtree(ns, 0);
  int widest = 1;
  bool ordered = true;  // children numbered before their parents
  for (int s = 0; s < nsuper_; ++s)
    for (int k = f.super[s]; k < f.super[s + 1]; ++k) col_super[at(k)] = s;
  for (int s = 0; s < nsuper_; ++s) {
    const int nscol = f.super[s + 1] - f.super[s];
    const int nsrow = f.pi[s + 1] - f.pi[s];
    widest = std::max(widest, nsrow);
    subtree[at(s)] = static_cast<double>(nsrow) * nscol;
    first[at(s)] = s;
    if (nsrow > nscol) parent[at(s)] = col_super[at(f.s_rows[f.pi[s] + nscol])];
    if (parent[at(s)] >= 0 && parent[at(s)] <= s) ordered = false;
  }
  std::vector<int> roots, count(ns, 1);
  for (int s = 0; s < nsuper_ && ordered; ++s) {
    const int p = parent[at(s)];
    if (p < 0) {
      roots.push_back(s);
      continue;
    }
    subtree[at(p)] += subtree[at(s)];
    first[at(p)] = std::min(first[at(p)], first[at(s)]);
    count[at(p)] += count[at(s)];
    children[at(p)].push_back(s);
  }
  // A thread's subtree is the range [first, root]: the tree must be postordered (CHOLMOD's
  // default); otherwise everything is solved in order on one thread.
  for (int s = 0; s < nsuper_ && ordered; ++s) ordered = count[at(s)] == s - first[at(s)] + 1;
  if (!ordered) roots.clear();
  // Proportional mapping on two threads: give each thread whole subtrees, and leave the
  // supernodes above them (the separators) to one thread after both. Start from the roots and
  // split the largest subtree into its children (its root joins the separators) while that
  // lowers the estimated time, separators + the larger thread's share. A thread's subtrees are
  // assigned largest first to the lighter thread.
  std::vector<int> candidates = roots;
  double top_work = 0;
  auto assign = [&](const std::vector<int>& subtrees, std::vector<int>(&groups)[2], double& worst) {
    std::vector<int> order = subtrees;
    std::sort(order.begin(), order.end(),
              [&](int a, int b) { return subtree[at(a)] > subtree[at(b)]; });
    double load[2] = {0, 0};
    groups[0].clear();
    groups[1].clear();
    for (const int r : order) {
      const int g = load[0] <= load[1] ? 0 : 1;
      load[g] += subtree[at(r)];
      groups[g].push_back(r);
    }
    worst = std::max(load[0], load[1]);
  };
  std::vector<int> groups[2], best_groups[2];
  double worst = 0;
  assign(candidates, groups, worst);
  double best = top_work + worst;
  best_groups[0] = groups[0];
  best_groups[1] = groups[1];
  for (int round = 0; round < 64 && !candidates.empty(); ++round) {
    const auto largest = std::max_element(candidates.begin(), candidates.end(), [&](int a, int b) {
      return subtree[at(a)] < subtree[at(b)];
    });
    const int r = *largest;
    candidates.erase(largest);
    top_work += subtree[at(r)];
    for (const int c : children[at(r)]) {
      top_work -= subtree[at(c)];
      candidates.push_back(c);
    }
    assign(candidates, groups, worst);
    if (top_work + worst < best) {
      best = top_work + worst;
      best_groups[0] = groups[0];
      best_groups[1] = groups[1];
    }
  }
  // Each group's subtrees as ranges of supernodes [first, root], in increasing order; the
  // separators are every supernode in no group.
  std::vector<char> in_group(ns, 0);
  for (int g = 0; g < 2; ++g) {
    ranges_[g].clear();
    std::sort(best_groups[g].begin(), best_groups[g].end());
    for (const int r : best_groups[g]) {
      ranges_[g].push_back({first[at(r)], r + 1});
      for (int s = first[at(r)]; s <= r; ++s) in_group[at(s)] = 1;
    }
  }
  top_.clear();
  top_row_.assign(at(n_), 0);
  for (int s = 0; s < nsuper_; ++s) {
    if (in_group[at(s)]) continue;
    top_.push_back(s);
    for (int k = f.super[s]; k < f.super[s + 1]; ++k) top_row_[at(k)] = 1;
  }
  parallel_ = !ranges_[0].empty() && !ranges_[1].empty() && n_ >= kParallelRows;
  y_.setZero(n_);
  buffer_.setZero(n_);
  for (VecX& v : scratch_) v.setZero(widest);
}

void SupernodalSolve::ForwardOne(const SupernodalFactorView& f, int s, int group) {
  double* y = y_.data();
  double* w = scratch_[group].data();
  const int k1 = f.super[s];
  const int nscol = f.super[s + 1] - k1;
  const int nsrow = f.pi[s + 1] - f.pi[s];
  const int m = nsrow - nscol;
  std::copy(y + k1, y + k1 + nscol, w);
  std::fill(w + nscol, w + nsrow, 0.0);
  (avx_ ? ForwardAvx : ForwardGeneric)(f.values + f.px[s], w, nsrow, nscol);
  std::copy(w, w + nscol, y + k1);
  const int* rows = f.s_rows + f.pi[s] + nscol;
  const double* update = w + nscol;  // −L₂₁ y₁
  if (group == 1) {
    // The second thread's updates of separator rows go to the buffer (the first thread may be
    // updating the same rows in y).
    double* buffer = buffer_.data();
    const char* top = top_row_.data();
    for (int i = 0; i < m; ++i) (top[rows[i]] ? buffer : y)[rows[i]] += update[i];
  } else {
    for (int i = 0; i < m; ++i) y[rows[i]] += update[i];
  }
}

void SupernodalSolve::BackwardOne(const SupernodalFactorView& f, int s, int group) {
  double* y = y_.data();
  double* w = scratch_[group].data();
  const int k1 = f.super[s];
  const int nscol = f.super[s + 1] - k1;
  const int nsrow = f.pi[s + 1] - f.pi[s];
  std::copy(y + k1, y + k1 + nscol, w);
  const int* rows = f.s_rows + f.pi[s] + nscol;
  for (int i = 0; i < nsrow - nscol; ++i) w[nscol + i] = y[rows[i]];
  (avx_ ? BackwardAvx : BackwardGeneric)(f.values + f.px[s], w, nsrow, nscol);
  std::copy(w, w + nscol, y + k1);
}

void SupernodalSolve::ForwardGroup(const SupernodalFactorView& f, int group) {
  for (const auto& [a, b] : ranges_[group])
    for (int s = a; s < b; ++s) ForwardOne(f, s, group);
}

void SupernodalSolve::BackwardGroup(const SupernodalFactorView& f, int group) {
  for (auto range = ranges_[group].rbegin(); range != ranges_[group].rend(); ++range)
    for (int s = range->second - 1; s >= range->first; --s) BackwardOne(f, s, group);
}

void SupernodalSolve::Separators(const SupernodalFactorView& f) {
  // The second group's buffered updates, then the separators forward and backward.
  double* y = y_.data();
  double* buffer = buffer_.data();
  for (const int s : top_)
    for (int k = f.super[s]; k < f.super[s + 1]; ++k) {
      y[k] += buffer[k];
      buffer[k] = 0;
    }
  for (const int s : top_) ForwardOne(f, s, 0);
  for (auto s = top_.rbegin(); s != top_.rend(); ++s) BackwardOne(f, *s, 0);
}

void SupernodalSolve::Solve(const SupernodalFactorView& f, const VecX& b, VecX& x) {
  GIPSI_CHECK(f.n == n_ && f.nsuper == nsuper_ && b.size() == n_,
              "SupernodalSolve: a factor or right-hand side of another size");
  avx_ = ActiveSimdKernels() == SimdKernels::kAvx;
  for (int k = 0; k < n_; ++k) y_[k] = b[f.perm ? f.perm[k] : k];
  auto serial = [&] {
    ForwardGroup(f, 0);
    ForwardGroup(f, 1);
    Separators(f);
    BackwardGroup(f, 1);
    BackwardGroup(f, 0);
  };
  if (parallel_ && omp_get_max_threads() >= 2 && !omp_in_parallel()) {
#pragma omp parallel num_threads(2)
    {
      if (omp_get_num_threads() < 2) {
        serial();
      } else {
        const int group = omp_get_thread_num();
        ForwardGroup(f, group);
#pragma omp barrier
#pragma omp master
        Separators(f);
#pragma omp barrier
        BackwardGroup(f, group);
      }
    }
  } else {
    serial();
  }
  if (x.size() != n_) x.resize(n_);
  for (int k = 0; k < n_; ++k) x[f.perm ? f.perm[k] : k] = y_[k];
}

}  // namespace gipsi
