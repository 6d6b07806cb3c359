#include "gipsi/numerics/sparse/saddle_point_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/SparseCholesky>

#include "gipsi/base/error.h"
#include "gipsi/numerics/sparse/solvers.h"

namespace gipsi {
namespace {

constexpr int kRestart = 40;  // Krylov vectors kept before a restart

/// The stored position of (row, col) in A, or -1.
int Position(const SparseMatrix& a, int row, int col) {
  const int* begin = a.innerIndexPtr() + a.outerIndexPtr()[col];
  const int* end = a.innerIndexPtr() + a.outerIndexPtr()[col + 1];
  const int* it = std::lower_bound(begin, end, row);
  return it != end && *it == row ? static_cast<int>(it - a.innerIndexPtr()) : -1;
}

/// The block of A with rows in [r0, r1) and columns in [0, nc), as a matrix with its own pattern,
/// and for each of its values the position of the same entry in A.
SparseMatrix Block(const SparseMatrix& a, int r0, int r1, int nc, std::vector<int>& from) {
  std::vector<Eigen::Triplet<double, int>> entries;
  from.clear();
  for (int c = 0; c < nc; ++c)
    for (int k = a.outerIndexPtr()[c]; k < a.outerIndexPtr()[c + 1]; ++k) {
      const int r = a.innerIndexPtr()[k];
      if (r >= r0 && r < r1) entries.emplace_back(r - r0, c, 1.0);
    }
  SparseMatrix block(r1 - r0, nc);
  block.setFromTriplets(entries.begin(), entries.end());
  block.makeCompressed();
  for (int c = 0; c < nc; ++c)
    for (int k = block.outerIndexPtr()[c]; k < block.outerIndexPtr()[c + 1]; ++k)
      from.push_back(Position(a, block.innerIndexPtr()[k] + r0, c));
  return block;
}

}  // namespace

struct SaddlePointSolver::Impl {
  Index nu = 0, np = 0;
  LinearSolverOptions options;
  Eigen::SimplicialLLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>> schur;
  SparseMatrix schur_matrix;
  bool schur_dirty = false;
  std::unique_ptr<LinearSolver> primary;  // K̂
  SparseMatrix k, b;                      // K̂ and B, their values refreshed by Factorize
  std::vector<int> k_from, k_from_t, b_from;
  const SparseMatrix* a = nullptr;
  bool refactorized = false;
  // GMRES work, sized by AnalyzePattern.
  Eigen::MatrixXd v, h;
  VecX cs, sn, g, y, w, z, r, xu, zu, tp, sp;

  /// z = P⁻¹ x; false if the K̂ solve produced non-finite values.
  bool Precondition(const Eigen::Ref<const VecX>& x, VecX& out) {
    xu = x.head(nu);
    primary->Solve(xu, zu);
    if (!zu.allFinite()) return false;
    tp.noalias() = b * zu;
    tp -= x.tail(np);
    out.head(nu) = zu;
    sp = schur.solve(tp);
    out.tail(np) = sp;
    return out.allFinite();
  }
};

SaddlePointSolver::SaddlePointSolver(Index num_primary, const SparseMatrix& schur,
                                     const LinearSolverOptions& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->nu = num_primary;
  impl_->np = schur.rows();
  impl_->options = options;
  impl_->schur_matrix = schur;
  impl_->schur.compute(schur);
  if (impl_->schur.info() != Eigen::Success)
    throw InputError("schur_gmres: the Schur complement's approximation is not positive definite");
  LinearSolverOptions primary;
  primary.type = "cholmod";
  primary.tolerance = 1e-6;  // judges only its own `converged`, which a preconditioner ignores
  impl_->primary = MakeCholmodSolver(primary);
  impl_->primary->AcceptIndefinite();
}

SaddlePointSolver::~SaddlePointSolver() = default;

void SaddlePointSolver::UpdateSchur(const SparseMatrix& schur) {
  GIPSI_CHECK(schur.nonZeros() == impl_->schur_matrix.nonZeros(),
              "schur_gmres UpdateSchur: another pattern");
  std::copy(schur.valuePtr(), schur.valuePtr() + schur.nonZeros(), impl_->schur_matrix.valuePtr());
  impl_->schur_dirty = true;
}

void SaddlePointSolver::AnalyzePattern(const SparseMatrix& A) {
  Impl& m = *impl_;
  GIPSI_CHECK(A.rows() == A.cols() && A.isCompressed() && A.rows() == m.nu + m.np,
              "schur_gmres: a {} by {} matrix for {} + {} unknowns", A.rows(), A.cols(), m.nu,
              m.np);
  const int nu = static_cast<int>(m.nu);
  const int n = static_cast<int>(A.rows());
  m.k = Block(A, 0, nu, nu, m.k_from);
  m.k_from_t.clear();
  for (int c = 0; c < nu; ++c)
    for (int k = m.k.outerIndexPtr()[c]; k < m.k.outerIndexPtr()[c + 1]; ++k) {
      const int t = Position(A, c, m.k.innerIndexPtr()[k]);
      GIPSI_CHECK(t >= 0, "schur_gmres: the displacement block's pattern is not symmetric");
      m.k_from_t.push_back(t);
    }
  m.b = Block(A, nu, n, nu, m.b_from);
  m.primary->AnalyzePattern(m.k);
  m.v.resize(n, kRestart + 1);
  m.h.resize(kRestart + 1, kRestart);
  m.cs.resize(kRestart);
  m.sn.resize(kRestart);
  m.g.resize(kRestart + 1);
  m.y.resize(kRestart);
  m.w.resize(n);
  m.sp.resize(m.np);
  m.z.resize(n);
  m.r.resize(n);
  m.tp.resize(m.np);
  m.a = nullptr;
}

bool SaddlePointSolver::Factorize(const SparseMatrix& A) {
  Impl& m = *impl_;
  if (m.k.rows() == 0) AnalyzePattern(A);
  m.a = nullptr;
  m.refactorized = true;
  if (!AllValuesFinite(A)) return false;
  const double* values = A.valuePtr();
  double* kv = m.k.valuePtr();
  for (std::size_t j = 0; j < m.k_from.size(); ++j)
    kv[j] = 0.5 * (values[m.k_from[j]] + values[m.k_from_t[j]]);
  if (augmentation_ != nullptr)
    for (std::size_t j = 0; j < m.k_from.size(); ++j) kv[j] += augmentation_[m.k_from[j]];
  double* bv = m.b.valuePtr();
  for (std::size_t j = 0; j < m.b_from.size(); ++j) bv[j] = values[m.b_from[j]];
  if (!m.primary->Factorize(m.k)) return false;
  if (m.schur_dirty) {
    m.schur.factorize(m.schur_matrix);
    m.schur_dirty = false;
    if (m.schur.info() != Eigen::Success) return false;
  }
  m.a = &A;
  return true;
}

LinearSolveStats SaddlePointSolver::Solve(const VecX& rhs, VecX& x) {
  Impl& m = *impl_;
  LinearSolveStats stats;
  stats.refactorized = m.refactorized;
  m.refactorized = false;
  stats.relative_residual = std::numeric_limits<double>::infinity();
  if (m.a == nullptr) return stats;
  const SparseMatrix& A = *m.a;
  GIPSI_CHECK(rhs.size() == A.rows(), "schur_gmres Solve: b has size {}, matrix has {} rows",
              rhs.size(), A.rows());
  x.setZero(A.rows());
  const double b_norm = rhs.norm();
  if (b_norm == 0) {
    stats.converged = true;
    stats.relative_residual = 0;
    return stats;
  }
  if (!std::isfinite(b_norm)) return stats;
  const double target = m.options.tolerance * b_norm;
  m.r = rhs;
  double r_norm = b_norm;
  while (stats.iterations < m.options.max_iterations) {
    // One cycle of right-preconditioned GMRES from x: A P⁻¹ u = r, x += P⁻¹ u.
    m.v.col(0) = m.r / r_norm;
    m.g.setZero();
    m.g[0] = r_norm;
    int j = 0;
    for (; j < kRestart && stats.iterations < m.options.max_iterations; ++j) {
      ++stats.iterations;
      if (!m.Precondition(m.v.col(j), m.z)) return stats;
      m.w.noalias() = A * m.z;
      for (int i = 0; i <= j; ++i) {  // modified Gram–Schmidt
        m.h(i, j) = m.w.dot(m.v.col(i));
        m.w -= m.h(i, j) * m.v.col(i);
      }
      m.h(j + 1, j) = m.w.norm();
      if (m.h(j + 1, j) > 0) m.v.col(j + 1) = m.w / m.h(j + 1, j);
      for (int i = 0; i < j; ++i) {  // the earlier Givens rotations
        const double t = m.cs[i] * m.h(i, j) + m.sn[i] * m.h(i + 1, j);
        m.h(i + 1, j) = -m.sn[i] * m.h(i, j) + m.cs[i] * m.h(i + 1, j);
        m.h(i, j) = t;
      }
      const double d = std::hypot(m.h(j, j), m.h(j + 1, j));
      if (!(d > 0) || !std::isfinite(d)) return stats;
      m.cs[j] = m.h(j, j) / d;
      m.sn[j] = m.h(j + 1, j) / d;
      m.h(j, j) = d;
      m.h(j + 1, j) = 0;
      m.g[j + 1] = -m.sn[j] * m.g[j];
      m.g[j] *= m.cs[j];
      if (std::abs(m.g[j + 1]) <= target) {
        ++j;
        break;
      }
    }
    // u = V y with H y = g (upper triangular), x += P⁻¹ u.
    m.y.head(j) = m.g.head(j);  // y is sized once (AnalyzePattern)
    auto y = m.y.head(j);
    m.h.topLeftCorner(j, j).triangularView<Eigen::Upper>().solveInPlace(y);
    m.w.noalias() = m.v.leftCols(j) * y;
    if (!m.Precondition(m.w, m.z)) return stats;
    x += m.z;
    m.r.noalias() = A * x;
    m.r = rhs - m.r;
    r_norm = m.r.norm();
    stats.relative_residual = r_norm / b_norm;
    if (!std::isfinite(r_norm)) return stats;
    if (r_norm <= target) {
      stats.converged = true;
      return stats;
    }
  }
  return stats;
}

}  // namespace gipsi
