#pragma once
/// @file
/// `SupernodalSolve`: the two triangular solves with a supernodal Cholesky factor
/// A = Pᵀ L Lᵀ P (CHOLMOD's layout), with the two largest subtrees of the elimination tree on
/// two threads.
///
/// A nested-dissection ordering (METIS) numbers the two halves of the mesh first and their
/// separator last, so the supernodes split into two independent groups below the separator:
/// the forward solve L z = P b runs each group on its own thread, then the separator's
/// supernodes; the backward solve Lᵀ w = z runs the separator, then the two groups in
/// parallel. The only rows both groups update in the forward solve are the separator's: the
/// second group accumulates its updates there in a buffer of its own, added once both are
/// done. The arithmetic is the same on one thread or two (the groups run one after the other
/// on one thread, with the same buffer), so the result does not depend on the thread count.
///
/// CHOLMOD's own `cholmod_solve` runs on one thread, and the back-substitutions of a kept
/// factorisation are most of the fine heart's linear solves (docs/performance.md).

#include <cstdint>
#include <utility>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A supernodal LLᵀ factor as CHOLMOD stores it (cholmod_factor with is_super, is_ll, int
/// indices, real double values), by pointers into the factor. Supernode s holds the columns
/// super[s] … super[s+1] − 1; its row indices are s_rows[pi[s]] … s_rows[pi[s+1] − 1], the
/// first of them its own columns; its values are the column-major block of pi[s+1] − pi[s]
/// rows at values + px[s]. perm: row k of L is row perm[k] of A.
struct SupernodalFactorView {
  int n = 0;
  int nsuper = 0;
  const int* super = nullptr;
  const int* pi = nullptr;
  const int* px = nullptr;
  const int* s_rows = nullptr;
  const double* values = nullptr;
  const int* perm = nullptr;
};

/// Not thread-safe; one per factor structure.
class SupernodalSolve {
 public:
  /// Reads the structure (once per symbolic analysis: super, pi, px, s_rows and perm must not
  /// change until the next Analyze) and chooses the two groups.
  void Analyze(const SupernodalFactorView& factor);
  /// x = A⁻¹ b with the current values (factor.values may move between factorisations).
  /// Allocates nothing. Uses two OpenMP threads when the team has them and the factor is
  /// large enough to pay for waking the second.
  void Solve(const SupernodalFactorView& factor, const VecX& b, VecX& x);

 private:
  int n_ = 0, nsuper_ = 0;
  std::vector<std::pair<int, int>> ranges_[2];  // each thread's subtrees: [first, last) supernodes
  std::vector<int> top_;                        // the separators' supernodes, increasing
  std::vector<char> top_row_;                   // rows (columns of L) of the separators
  bool parallel_ = false;
  bool avx_ = false;  // the AVX kernels (the same bits; numerics/simd.h)
  VecX y_;            // the permuted right-hand side, solved in place
  VecX buffer_;       // the second thread's updates of separator rows
  VecX scratch_[2];   // per-thread work vectors (the tallest supernode)

  void ForwardOne(const SupernodalFactorView& f, int s, int group);
  void BackwardOne(const SupernodalFactorView& f, int s, int group);
  void ForwardGroup(const SupernodalFactorView& f, int group);
  void BackwardGroup(const SupernodalFactorView& f, int group);
  /// Adds the buffered updates and solves the separators, forward then backward.
  void Separators(const SupernodalFactorView& f);
};

}  // namespace gipsi
GIPSI_EXPORT_END
