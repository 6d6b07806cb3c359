// Smoothed-aggregation AMG: hierarchy set-up (strength graph, aggregation, tentative and
// smoothed prolongators, Galerkin products) and the symmetric damped-Jacobi V-cycle.

#include "gipsi/numerics/sparse/amg.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/CholmodSupport>

#include "gipsi/base/error.h"
#include "gipsi/numerics/sparse/serial_openmp.h"
#include "gipsi/numerics/sparse/solvers.h"
#include "gipsi/numerics/sparse/vector_ops.h"

namespace gipsi {
namespace {

using Triplet = Eigen::Triplet<double, int>;

/// Node-to-node coupling graph of A for nodes given by `node_start` (node I owns rows
/// node_start[I] .. node_start[I+1]): J is a neighbour of I ≠ J if block A_IJ has a nonzero.
/// CSR (start, list); each list is sorted.
struct NodeGraph {
  std::vector<int> start;
  std::vector<int> list;
};

NodeGraph BuildNodeGraph(const SparseMatrix& A, const std::vector<int>& node_start) {
  const int nodes = static_cast<int>(node_start.size()) - 1;
  std::vector<int> node_of(static_cast<std::size_t>(A.rows()));
  for (int n = 0; n < nodes; ++n)
    for (int i = node_start[static_cast<std::size_t>(n)];
         i < node_start[static_cast<std::size_t>(n) + 1]; ++i)
      node_of[static_cast<std::size_t>(i)] = n;
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* values = A.valuePtr();
  NodeGraph graph;
  graph.start.assign(static_cast<std::size_t>(nodes) + 1, 0);
  std::vector<int> marker(static_cast<std::size_t>(nodes), -1);
  for (int n = 0; n < nodes; ++n) {
    const std::size_t first = graph.list.size();
    for (int c = node_start[static_cast<std::size_t>(n)];
         c < node_start[static_cast<std::size_t>(n) + 1]; ++c)
      for (int k = outer[c]; k < outer[c + 1]; ++k) {
        const int m = node_of[static_cast<std::size_t>(inner[k])];
        if (m == n || values[k] == 0.0 || marker[static_cast<std::size_t>(m)] == n) continue;
        marker[static_cast<std::size_t>(m)] = n;
        graph.list.push_back(m);
      }
    std::sort(graph.list.begin() + static_cast<std::ptrdiff_t>(first), graph.list.end());
    graph.start[static_cast<std::size_t>(n) + 1] = static_cast<int>(graph.list.size());
  }
  return graph;
}

/// Aggregate of each node (−1: isolated, in none); returns the aggregate count.
int Aggregate(const NodeGraph& graph, std::vector<int>& aggregate) {
  const int nodes = static_cast<int>(graph.start.size()) - 1;
  constexpr int kFree = -1;
  constexpr int kIsolated = -2;
  aggregate.assign(static_cast<std::size_t>(nodes), kFree);
  auto neighbours = [&](int n) {
    return std::pair(graph.list.begin() + graph.start[static_cast<std::size_t>(n)],
                     graph.list.begin() + graph.start[static_cast<std::size_t>(n) + 1]);
  };
  for (int n = 0; n < nodes; ++n)
    if (graph.start[static_cast<std::size_t>(n)] == graph.start[static_cast<std::size_t>(n) + 1])
      aggregate[static_cast<std::size_t>(n)] = kIsolated;
  int count = 0;
  // Pass 1: a free node whose neighbours are all free seeds an aggregate with them.
  for (int n = 0; n < nodes; ++n) {
    if (aggregate[static_cast<std::size_t>(n)] != kFree) continue;
    const auto [begin, end] = neighbours(n);
    if (std::any_of(begin, end, [&](int m) { return aggregate[static_cast<std::size_t>(m)] >= 0; }))
      continue;
    aggregate[static_cast<std::size_t>(n)] = count;
    for (auto it = begin; it != end; ++it) aggregate[static_cast<std::size_t>(*it)] = count;
    ++count;
  }
  // Pass 2: a free node joins the aggregate of its first neighbour aggregated in pass 1.
  const std::vector<int> first_pass = aggregate;
  for (int n = 0; n < nodes; ++n) {
    if (aggregate[static_cast<std::size_t>(n)] != kFree) continue;
    const auto [begin, end] = neighbours(n);
    for (auto it = begin; it != end; ++it)
      if (first_pass[static_cast<std::size_t>(*it)] >= 0) {
        aggregate[static_cast<std::size_t>(n)] = first_pass[static_cast<std::size_t>(*it)];
        break;
      }
  }
  // Pass 3: what is left forms aggregates with its free neighbours.
  for (int n = 0; n < nodes; ++n) {
    if (aggregate[static_cast<std::size_t>(n)] != kFree) continue;
    aggregate[static_cast<std::size_t>(n)] = count;
    const auto [begin, end] = neighbours(n);
    for (auto it = begin; it != end; ++it)
      if (aggregate[static_cast<std::size_t>(*it)] == kFree)
        aggregate[static_cast<std::size_t>(*it)] = count;
    ++count;
  }
  for (int& a : aggregate)
    if (a == kIsolated) a = -1;
  return count;
}

/// The tentative prolongator T (rows of A by coarse DOFs, orthonormal columns per aggregate),
/// the coarse near-null space and the coarse node partition, from the aggregates and the
/// near-null space B of this level.
struct Tentative {
  SparseMatrix t;
  Eigen::MatrixXd coarse_null;
  std::vector<int> coarse_start;
};

Tentative FitCandidates(const std::vector<int>& node_start, const std::vector<int>& aggregate,
                        int aggregates, const Eigen::MatrixXd& B) {
  const int nodes = static_cast<int>(node_start.size()) - 1;
  const Index k = B.cols();
  // Rows of each aggregate, in node order.
  std::vector<std::vector<int>> rows(static_cast<std::size_t>(aggregates));
  for (int n = 0; n < nodes; ++n) {
    const int a = aggregate[static_cast<std::size_t>(n)];
    if (a < 0) continue;
    for (int i = node_start[static_cast<std::size_t>(n)];
         i < node_start[static_cast<std::size_t>(n) + 1]; ++i)
      rows[static_cast<std::size_t>(a)].push_back(i);
  }
  Tentative out;
  out.coarse_start.push_back(0);
  std::vector<Triplet> triplets;
  std::vector<Eigen::MatrixXd> coarse_rows;
  for (const std::vector<int>& agg_rows : rows) {
    const Index m = static_cast<Index>(agg_rows.size());
    Eigen::MatrixXd local(m, k);
    for (Index i = 0; i < m; ++i) local.row(i) = B.row(agg_rows[static_cast<std::size_t>(i)]);
    // Modified Gram–Schmidt with one re-orthogonalisation; a column whose remainder is below
    // 1e-8 of its norm is dependent on the earlier ones (e.g. a rotation about the line
    // through a two-node aggregate) and adds no coarse DOF.
    Eigen::MatrixXd q(m, k);
    Eigen::MatrixXd r = Eigen::MatrixXd::Zero(k, k);
    Index kept = 0;
    for (Index j = 0; j < k; ++j) {
      Eigen::VectorXd v = local.col(j);
      const double norm0 = v.norm();
      for (int pass = 0; pass < 2; ++pass)
        for (Index c = 0; c < kept; ++c) {
          const double coef = q.col(c).dot(v);
          v -= coef * q.col(c);
          r(c, j) += coef;
        }
      const double norm = v.norm();
      if (norm0 == 0.0 || norm <= 1e-8 * norm0) continue;
      q.col(kept) = v / norm;
      r(kept, j) = norm;
      ++kept;
    }
    if (kept == 0) continue;
    const int first = out.coarse_start.back();
    for (Index i = 0; i < m; ++i)
      for (Index c = 0; c < kept; ++c)
        triplets.emplace_back(agg_rows[static_cast<std::size_t>(i)], first + static_cast<int>(c),
                              q(i, c));
    coarse_rows.push_back(r.topRows(kept));
    out.coarse_start.push_back(first + static_cast<int>(kept));
  }
  const Index coarse = out.coarse_start.back();
  out.t.resize(static_cast<Index>(B.rows()), coarse);
  out.t.setFromTriplets(triplets.begin(), triplets.end());
  out.t.makeCompressed();
  out.coarse_null.resize(coarse, k);
  Index row = 0;
  for (const Eigen::MatrixXd& block : coarse_rows) {
    out.coarse_null.middleRows(row, block.rows()) = block;
    row += block.rows();
  }
  return out;
}

/// Largest eigenvalue of D⁻¹A (D = diag A) by 20 power iterations on the symmetric
/// D^-1/2 A D^-1/2 from a fixed start vector (a slight underestimate).
double SpectralRadiusEstimate(const SparseMatrix& A, const VecX& inverse_diagonal) {
  const Index n = A.rows();
  const VecX scale = inverse_diagonal.cwiseSqrt();
  VecX v(n), w(n), y(n);
  for (Index i = 0; i < n; ++i) v[i] = 1.0 + 0.5 * std::sin(0.7 * static_cast<double>(i));
  v.normalize();
  double rho = 0.0;
  for (int it = 0; it < 20; ++it) {
    w = scale.cwiseProduct(v);
    SymmetricSpMV(A, w, y);
    y = scale.cwiseProduct(y);
    rho = v.dot(y);
    const double norm = y.norm();
    if (!(norm > 0.0)) break;
    v = y / norm;
  }
  return rho;
}

/// y = M x for a row-major M (each row summed by one thread).
void RowSpMV(const Eigen::SparseMatrix<double, Eigen::RowMajor, int>& M, const VecX& x, VecX& y,
             bool accumulate) {
  const int n = static_cast<int>(M.rows());
  const int* __restrict outer = M.outerIndexPtr();
  const int* __restrict inner = M.innerIndexPtr();
  const double* __restrict values = M.valuePtr();
  const double* __restrict px = x.data();
  double* __restrict py = y.data();
  ForRange(0, n, n >= kMinParallelLength, [=](int i) {
    double s = 0.0;
    for (int k = outer[i]; k < outer[i + 1]; ++k) s += values[k] * px[inner[k]];
    py[i] = accumulate ? py[i] + s : s;
  });
}

}  // namespace

struct SmoothedAggregationAmg::CoarseSolver {
  Eigen::CholmodSupernodalLLT<SparseMatrix, Eigen::Lower> llt;
};

SmoothedAggregationAmg::SmoothedAggregationAmg() = default;
SmoothedAggregationAmg::~SmoothedAggregationAmg() = default;

void SmoothedAggregationAmg::SetNearNullSpace(const Eigen::MatrixXd& modes) {
  GIPSI_CHECK(modes.cols() <= 12, "AMG near-null space: at most 12 vectors, got {}", modes.cols());
  near_null_ = modes;
}

Index SmoothedAggregationAmg::rows(int level) const {
  return levels_[static_cast<std::size_t>(level)]->a->rows();
}

double SmoothedAggregationAmg::operator_complexity() const {
  if (levels_.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& level : levels_) sum += static_cast<double>(level->a->nonZeros());
  return sum / static_cast<double>(levels_.front()->a->nonZeros());
}

void SmoothedAggregationAmg::DetectBlocks(Level& level) {
  const SparseMatrix& A = *level.a;
  level.blocked = false;
  if (!level.sorted || !HasNodeBlockPattern(A)) return;
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const int nodes = static_cast<int>(A.rows() / 3);
  std::vector<int> offsets(static_cast<std::size_t>(nodes), -1);
  for (int node = 0; node < nodes; ++node)
    for (int t = outer[3 * node]; t < outer[3 * node + 1]; t += 3)
      if (inner[t] == 3 * node) offsets[static_cast<std::size_t>(node)] = t - outer[3 * node];
  level.block_diagonal = std::move(offsets);
  level.block_inverse.assign(static_cast<std::size_t>(9 * nodes), 0.0);
  level.copy.AssignPattern(A);  // the values come with UpdateDiagonal
  level.blocked = true;
}

bool SmoothedAggregationAmg::UpdateDiagonal(Level& level) const {
  const SparseMatrix& A = *level.a;
  const double* values = A.valuePtr();
  if (level.blocked) {
    const int* outer = A.outerIndexPtr();
    const int nodes = static_cast<int>(level.block_diagonal.size());
    level.copy.CopyValues(A);
    bool positive = true;
    for (int node = 0; node < nodes; ++node) {
      Mat3 block;
      for (int a = 0; a < 3; ++a)
        for (int i = 0; i < 3; ++i)
          block(i, a) = values[outer[3 * node + a] +
                               level.block_diagonal[static_cast<std::size_t>(node)] + i];
      // An SPD matrix has SPD diagonal blocks; the Cholesky test rejects anything else.
      const Eigen::LLT<Mat3> llt(block);
      const bool ok = llt.info() == Eigen::Success && block.allFinite();
      positive = positive && ok;
      Eigen::Map<Mat3> inverse(level.block_inverse.data() + 9 * node);
      inverse = ok ? Mat3(llt.solve(Mat3::Identity())) : Mat3::Zero();
      inverse = 0.5 * (inverse + inverse.transpose()).eval();  // exactly symmetric
    }
    return positive;
  }
  bool positive = true;
  for (std::size_t i = 0; i < level.diagonal.size(); ++i) {
    const double d = level.diagonal[i] >= 0 ? values[level.diagonal[i]] : 0.0;
    positive = positive && d > 0.0 && std::isfinite(d);
    level.inverse_diagonal[static_cast<Index>(i)] = d > 0.0 ? 1.0 / d : 0.0;
  }
  return positive;
}

bool SmoothedAggregationAmg::Setup(const SparseMatrix& A) {
  GIPSI_CHECK(A.rows() == A.cols() && A.isCompressed(), "AMG: matrix must be square, compressed");
  ready_ = false;
  levels_.clear();
  coarse_.reset();
  if (!AllValuesFinite(A)) return false;
  const Index n = A.rows();
  const int block = n % 3 == 0 ? 3 : 1;
  std::vector<int> node_start(static_cast<std::size_t>(n / block) + 1);
  for (std::size_t i = 0; i < node_start.size(); ++i) node_start[i] = static_cast<int>(i) * block;
  Eigen::MatrixXd null_space;
  if (near_null_.rows() == n && near_null_.cols() > 0) {
    null_space = near_null_;
  } else {
    null_space = Eigen::MatrixXd::Zero(n, block);
    for (Index i = 0; i < n; ++i) null_space(i, i % block) = 1.0;
  }

  SparseMatrix next;  // the coarse matrix being built, moved into its level
  for (;;) {
    levels_.push_back(std::make_unique<Level>());
    Level& level = *levels_.back();
    if (levels_.size() == 1) {
      level.a = &A;
    } else {
      level.owned = std::move(next);
      level.a = &level.owned;
    }
    const SparseMatrix& current = *level.a;
    const Index rows = current.rows();
    level.diagonal.assign(static_cast<std::size_t>(rows), -1);
    level.sorted = true;
    for (int j = 0; j < static_cast<int>(rows); ++j)
      for (int k = current.outerIndexPtr()[j]; k < current.outerIndexPtr()[j + 1]; ++k) {
        if (current.innerIndexPtr()[k] == j) level.diagonal[static_cast<std::size_t>(j)] = k;
        if (k > current.outerIndexPtr()[j] &&
            current.innerIndexPtr()[k] <= current.innerIndexPtr()[k - 1])
          level.sorted = false;
      }
    level.inverse_diagonal.resize(rows);
    if (levels_.size() == 1) DetectBlocks(level);  // coarse nodes have ≤ 6 DOFs: point-wise
    if (!UpdateDiagonal(level)) return false;
    for (VecX* v : {&level.x, &level.b, &level.residual}) v->setZero(rows);
    if (rows <= kMaxCoarseRows || static_cast<int>(levels_.size()) >= kMaxLevels) break;

    const NodeGraph graph = BuildNodeGraph(current, node_start);
    std::vector<int> aggregate;
    const int aggregates = Aggregate(graph, aggregate);
    Tentative tentative = FitCandidates(node_start, aggregate, aggregates, null_space);
    const Index coarse_rows = tentative.t.cols();
    if (coarse_rows == 0 || 10 * coarse_rows >= 9 * rows) break;  // coarsening stagnates

    if (level.blocked) {  // the prolongator smoother uses the point diagonal
      for (Index i = 0; i < rows; ++i) {
        const double d = current.valuePtr()[level.diagonal[static_cast<std::size_t>(i)]];
        level.inverse_diagonal[i] = 1.0 / d;  // > 0: the diagonal blocks are SPD
      }
    }
    const double rho = SpectralRadiusEstimate(current, level.inverse_diagonal);
    const double omega = rho > 0.0 ? 4.0 / (3.0 * rho) : 0.0;
    level.jacobi_weight = JacobiWeight(level, rho);
    const SparseMatrix at = current * tentative.t;
    SparseMatrix p = tentative.t - SparseMatrix((omega * level.inverse_diagonal).asDiagonal() * at);
    p.makeCompressed();
    const SparseMatrix ap = current * p;
    const SparseMatrix pt = p.transpose();
    const SparseMatrix galerkin = pt * ap;
    const SparseMatrix galerkin_t = galerkin.transpose();
    // Symmetrised to remove the products' round-off. (Dropping weak coarse entries, lumped
    // onto the diagonal to stay SPD, was tried: at 0.005 √(a_ii a_jj) it halved the coarse
    // nonzeros of the FEM benchmark but raised CG iterations from 19 to 31 at 78k tets and
    // gave no net gain at 0.001, so every entry is kept.)
    next = 0.5 * (galerkin + galerkin_t);
    next.makeCompressed();
    level.p = p;
    level.r = pt;
    null_space = std::move(tentative.coarse_null);
    node_start = std::move(tentative.coarse_start);
  }
  coarse_ = std::make_unique<CoarseSolver>();
  coarse_->llt.cholmod().print = 0;  // failures are reported through the return value
  {
    const SerialOpenMp serial;  // serial_openmp.h: CHOLMOD's fixed 4-thread regions
    coarse_->llt.compute(*levels_.back()->a);
  }
  if (coarse_->llt.info() != Eigen::Success) return false;
  ready_ = true;
  return true;
}

bool SmoothedAggregationAmg::Refresh(const SparseMatrix& A) {
  GIPSI_CHECK(!levels_.empty(), "AMG Refresh before Setup");
  Level& fine = *levels_.front();
  CheckAnalysedShape(A, fine.a->rows(), fine.a->nonZeros(), "AMG Refresh");
  ready_ = false;
  if (!AllValuesFinite(A)) return false;
  fine.a = &A;
  if (!UpdateDiagonal(fine)) return false;
  ready_ = coarse_ != nullptr && coarse_->llt.info() == Eigen::Success;
  return ready_;
}

void SmoothedAggregationAmg::Apply(const VecX& r, VecX& z) {
  GIPSI_CHECK(ready_, "AMG Apply without a successful Setup or Refresh");
  Level& fine = *levels_.front();
  GIPSI_CHECK(r.size() == fine.a->rows() && z.size() == r.size(), "AMG Apply: size mismatch");
  fine.b = r;
  Cycle(0);
  z = fine.x;
}

namespace {

/// x_I = M s for the symmetric 3×3 M (column-major); `add` accumulates instead.
inline void ApplyInverse(const double* __restrict m, const double s[3], double* __restrict x,
                         bool add) {
  const double y0 = m[0] * s[0] + m[3] * s[1] + m[6] * s[2];
  const double y1 = m[1] * s[0] + m[4] * s[1] + m[7] * s[2];
  const double y2 = m[2] * s[0] + m[5] * s[1] + m[8] * s[2];
  if (add) {
    x[0] += y0;
    x[1] += y1;
    x[2] += y2;
  } else {
    x[0] = y0;
    x[1] = y1;
    x[2] = y2;
  }
}

}  // namespace

bool SmoothedAggregationAmg::Multiply(const VecX& x, VecX& y) const {
  if (levels_.empty() || !levels_.front()->blocked) return false;
  const Level& level = *levels_.front();
  GIPSI_CHECK(x.size() == level.a->rows() && y.size() == x.size() && x.data() != y.data(),
              "AMG Multiply: sizes do not match or x and y alias");
  LevelMultiply(level, x, y);
  return true;
}

double SmoothedAggregationAmg::JacobiWeight(Level& level, double point_rho) {
  // ω = 4 / (3 λ), λ ≈ λ_max(D⁻¹A) for the smoother's D (3×3 blocks or the point diagonal),
  // raised by 10 % over the power iteration's estimate (which approaches it from below) so
  // that ω λ_max < 2 (damped Jacobi converges, the cycle stays SPD) even after the finest
  // matrix drifts by a few per cent under a lagged hierarchy.
  double rho = point_rho;
  if (level.blocked) {
    const Index n = level.a->rows();
    VecX v(n), w(n), z(n);
    for (Index i = 0; i < n; ++i) v[i] = 1.0 + 0.5 * std::sin(0.7 * static_cast<double>(i));
    v.normalize();
    for (int it = 0; it < 20; ++it) {
      SymmetricSpMV(*level.a, v, w);
      ApplyBlockInverse(level, w, z, 1.0, false);
      rho = z.norm();
      if (!(rho > 0.0)) break;
      v = z / rho;
    }
  }
  return rho > 0.0 ? 4.0 / (3.0 * 1.1 * rho) : 0.0;
}

void SmoothedAggregationAmg::ApplyBlockInverse(const Level& level, const VecX& r, VecX& z,
                                               double weight, bool add) {
  const Index n = r.size();
  const double* __restrict pr = r.data();
  double* __restrict pz = z.data();
  if (level.blocked) {
    const int nodes = static_cast<int>(n / 3);
    const double* __restrict inverse = level.block_inverse.data();
    ForRange(0, nodes, n >= kMinParallelLength, [=](int node) {
      const double s[3] = {weight * pr[3 * node], weight * pr[3 * node + 1],
                           weight * pr[3 * node + 2]};
      ApplyInverse(inverse + 9 * node, s, pz + 3 * node, add);
    });
    return;
  }
  const double* __restrict inv = level.inverse_diagonal.data();
  ForRange(Index{0}, n, n >= kMinParallelLength,
           [=](Index i) { pz[i] = (add ? pz[i] : 0.0) + weight * inv[i] * pr[i]; });
}

void SmoothedAggregationAmg::LevelMultiply(const Level& level, const VecX& x, VecX& y) {
  if (level.blocked) {
    level.copy.Multiply(x, y);
    return;
  }
  SymmetricSpMV(*level.a, x, y);
}

void SmoothedAggregationAmg::Cycle(std::size_t l) {
  Level& level = *levels_[l];
  if (l + 1 == levels_.size()) {
    const SerialOpenMp serial;
    level.x = coarse_->llt.solve(level.b);
    return;
  }
  // Damped (block) Jacobi before and after the coarse correction: the same symmetric smoother
  // on both sides, so the cycle is symmetric; every step is an SpMV or a diagonal scaling
  // (parallel, rows summed by one thread each).
  Level& coarse = *levels_[l + 1];
  const double w = level.jacobi_weight;
  ApplyBlockInverse(level, level.b, level.x, w, false);  // x = ω D⁻¹ b (from x = 0)
  LevelMultiply(level, level.x, level.residual);
  level.residual = level.b - level.residual;
  RowSpMV(level.r, level.residual, coarse.b, false);
  Cycle(l + 1);
  RowSpMV(level.p, coarse.x, level.x, true);
  LevelMultiply(level, level.x, level.residual);
  level.residual = level.b - level.residual;
  ApplyBlockInverse(level, level.residual, level.x, w, true);  // x += ω D⁻¹ (b − A x)
}

}  // namespace gipsi
