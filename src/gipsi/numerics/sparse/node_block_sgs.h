#pragma once
/// @file
/// `NodeBlockSgs`: the sweeps of conjugate gradients preconditioned by symmetric block
/// Gauss–Seidel on 3×3 node blocks, in Eisenstat's form, for a symmetric positive definite matrix
/// of 3×3 node blocks (an FEM tangent, HasNodeBlockPattern).
///
/// The preconditioner. Split A = L + D + U + C: D the 3×3 diagonal blocks, L and U the blocks
/// below and above them whose two nodes lie in one *domain* (a contiguous range of nodes), C
/// the blocks that couple two domains. M = (D + L) D⁻¹ (D + U) is one symmetric Gauss–Seidel
/// sweep per domain, the domains independent (block Jacobi across domains, Gauss–Seidel within:
/// the sweeps are sequential inside a domain, so the domains are what threads share). M is SPD
/// whenever A is.
///
/// Eisenstat's trick (S. C. Eisenstat, "Efficient implementation of a class of preconditioned
/// conjugate gradient methods", SIAM J. Sci. Stat. Comput. 2, 1981): CG on the split system
/// Â = W⁻¹ A W⁻ᵀ with W = (D + L) L_D⁻ᵀ (D = L_D L_Dᵀ) needs no product with A, because
/// A t = (D + L) t + (D + U) t − D t + C t. With P = L_D p and t = (D + U)⁻¹ P, one iteration is
/// - a backward sweep: P ← R + βP, then t_I = D_I⁻¹ (P_I − Σ_{J>I} A_IJ t_J) in the domain;
/// - a forward sweep: w_I = D_I⁻¹ (P_I + (C t)_I − Σ_{J<I} A_IJ u_J), u_I = w_I − t_I (w = t + u
///   is L_D⁻ᵀ Â p);
/// - an update: α = (R, Z) / (P, w); x += α t, Z −= α w, R = D Z (R = L_D ρ and Z = D⁻¹ R for
///   CG's residual ρ).
/// The residual b − A x equals W ρ = (D + L) Z (by induction: (D + L) w = A t), so the update
/// can also return ‖(D + L) Z‖, at the price of a second pass over the L blocks; the solver asks
/// for it only where the stopping test may decide (pcg.cc).
/// Every block is read once per iteration (lower and cross blocks by the forward sweep, upper
/// ones by the backward sweep), the memory traffic of one product with A, for 2.2-2.7× fewer
/// iterations than Jacobi on the FEM benchmark meshes (docs/performance.md). The blocks are
/// copied in the order the sweeps read them: the forward sweep's in node order, the backward
/// sweep's in reverse node order (each node's farthest block first), so both sweeps stream
/// through memory.
///
/// Each kernel covers one domain and sums in a fixed order, with its generic and AVX copies
/// doing the same IEEE operations (numerics/simd.h): the bits depend on the domain count, never
/// on the threads. Copyable (plain arrays).

#include <algorithm>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/numerics/sparse/linear_solver.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {
namespace sgs_detail {
struct Sweep;  // the kernels' view of the arrays (node_block_sgs.cc)
}

/// The number of domains "sgs" CG (pcg.cc) splits a matrix of `rows` unknowns into: one per
/// kSgsDomainRows rows, at least one. A function of the matrix only, never of the threads, so
/// that the bits do not depend on the thread count. Domains decouple the sweeps (threads can
/// share the work) but weaken the preconditioner: on the FEM benchmark's 20k-tet tangent
/// (14,739 rows) one domain took 51 iterations per step, two 67 (Jacobi 140); on the 78k-tet
/// one (52,728 rows) two took 99, four 103 and eight 115 (Jacobi 226). Systems below 2 ×
/// kSgsDomainRows rows keep one domain and solve on one thread.
inline constexpr Index kSgsDomainRows = 12288;
[[nodiscard]] inline int SgsDomainCount(Index rows) {
  return static_cast<int>(std::clamp<Index>(rows / kSgsDomainRows, 1, 1024));
}

/// Partial sums of one update sweep.
struct SgsUpdateSums {
  double rr = 0.0;  ///< (r, r) for r = (D + L) Z, the residual (0 unless asked for)
  double zr = 0.0;  ///< (Z, R) = (ρ, ρ): CG's γ
};

class NodeBlockSgs {
 public:
  /// Takes the pattern of A (HasNodeBlockPattern(A) must hold: checked) and splits its nodes
  /// into `domains` ≥ 1 contiguous ranges of about equal numbers of blocks (fewer if there are
  /// fewer nodes); sizes the work vectors. The values come with Factorize.
  void AssignPattern(const SparseMatrix& A, int domains);
  /// Copies the values of A (the pattern of the last AssignPattern: only the sizes are checked),
  /// in parallel over nodes unless `team` is false, and inverts the diagonal blocks through
  /// their Cholesky factors; false if one is not positive definite or not finite.
  [[nodiscard]] bool Factorize(const SparseMatrix& A, bool team = true);

  [[nodiscard]] int domains() const { return static_cast<int>(domain_start_.size()) - 1; }
  /// First node of domain d (d = domains(): the node count).
  [[nodiscard]] int domain_start(int d) const { return domain_start_[static_cast<std::size_t>(d)]; }

  /// The sweeps, each over the nodes of domain d (see the file comment); r and x have 3 ×
  /// nodes entries. Start: Z = (D + L)⁻¹ r, R = D Z, P = 0; returns (Z, R) over the domain.
  double Start(const double* r, int d);
  /// P ← R + βP, then t = (D + U)⁻¹ P, nodes in reverse order.
  void Backward(double beta, int d);
  /// w and u from P and t (t final in every domain); returns (P, w) over the domain.
  double Forward(int d);
  /// x += α t, Z −= α w, R = D Z; returns (Z, R) over the domain and, with `residual`, the
  /// squared norm of the residual r = (D + L) Z over the domain (else 0).
  SgsUpdateSums Update(double alpha, double* x, bool residual, int d);

  /// y = A x from the copied blocks (x and y: 3 × nodes entries, not aliased), parallel over
  /// nodes; each entry summed in a fixed order.
  void Multiply(const VecX& x, VecX& y);

 private:
  sgs_detail::Sweep MakeSweep();

  [[nodiscard]] int nodes() const { return static_cast<int>(lower_.size()); }

  std::vector<int> domain_start_;  ///< first node of each domain, then the node count
  /// Per node, its blocks as A's compressed columns list them (sorted by column J), counted
  /// from the node's first: the first inside its domain, the diagonal one, and one past the
  /// last inside its domain.
  std::vector<int> lower_, diagonal_, upper_end_;
  std::vector<int> source_;  ///< per node: where its first column starts in A's values
  /// The forward sweep's blocks, node by node: those coupling to other domains (C), then the
  /// lower ones in the domain (L, increasing J). Node I's are [forward_start_[I],
  /// forward_start_[I + 1]), its L blocks from forward_lower_[I].
  std::vector<int> forward_start_, forward_lower_, forward_column_;
  /// The backward sweep's blocks (U in the domain), node n − 1 first, each node's in decreasing
  /// J: node I's are [backward_start_[I + 1], backward_start_[I]) (backward_start_[n] = 0).
  std::vector<int> backward_start_, backward_column_;
  /// Blocks column-major (A(3I + a, 3J + i) at 9m + 3i + a), each array followed by padding:
  /// the forward and backward blocks, D_I and D_I⁻¹ (9 per node).
  std::vector<double> forward_values_, backward_values_, block_, inverse_;
  std::vector<double> z_, r_, p_, t_, u_, w_;  ///< Z, R, P, t, u, w (3 × nodes)
  Index nonzeros_ = 0;                         ///< of the analysed pattern
};

}  // namespace gipsi
GIPSI_EXPORT_END
