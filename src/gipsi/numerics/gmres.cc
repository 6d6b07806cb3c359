#include "gipsi/numerics/gmres.h"

#include <cmath>

#include "gipsi/base/error.h"

namespace gipsi {

void Gmres::Prepare(Index n, const GmresOptions& options) {
  GIPSI_CHECK(n >= 1 && options.restart >= 1 && options.max_iterations >= 1 &&
                  options.relative_tolerance > 0,
              "GMRES: size, restart, iterations and tolerance must be positive");
  options_ = options;
  const Index m = options.restart;
  basis_.setZero(n, m + 1);
  hessenberg_.setZero(m + 1, m);
  cos_.setZero(m);
  sin_.setZero(m);
  rhs_.setZero(m + 1);
  w_.setZero(n);
  r_.setZero(n);
  y_.setZero(m);
}

GmresResult Gmres::Solve(const Operator& apply, const VecX& b, VecX& x) {
  GIPSI_CHECK(b.size() == basis_.rows(), "GMRES prepared for {}, got {}", basis_.rows(), b.size());
  GmresResult result;
  x.setZero(b.size());
  const double b_norm = b.norm();
  if (b_norm == 0) {
    result.converged = true;
    return result;
  }
  if (!std::isfinite(b_norm)) return result;
  const double target = options_.relative_tolerance * b_norm;
  const Index m = options_.restart;
  r_ = b;  // the residual of x = 0
  while (result.iterations < options_.max_iterations) {
    const double beta = r_.norm();
    result.relative_residual = beta / b_norm;
    if (beta <= target) {
      result.converged = true;
      return result;
    }
    basis_.col(0) = r_ / beta;
    rhs_.setZero();
    rhs_[0] = beta;
    Index k = 0;  // Krylov dimension reached in this cycle
    double residual = beta;
    while (k < m && result.iterations < options_.max_iterations && residual > target) {
      apply(basis_.col(k), w_);
      ++result.iterations;
      if (!w_.allFinite()) return result;
      // Modified Gram–Schmidt against the basis so far.
      for (Index i = 0; i <= k; ++i) {
        const double h = basis_.col(i).dot(w_);
        hessenberg_(i, k) = h;
        w_.noalias() -= h * basis_.col(i);
      }
      const double h_next = w_.norm();
      hessenberg_(k + 1, k) = h_next;
      // Earlier rotations on the new column, then a new rotation to zero its subdiagonal.
      for (Index i = 0; i < k; ++i) {
        const double a = hessenberg_(i, k), c = hessenberg_(i + 1, k);
        hessenberg_(i, k) = cos_[i] * a + sin_[i] * c;
        hessenberg_(i + 1, k) = -sin_[i] * a + cos_[i] * c;
      }
      const double a = hessenberg_(k, k), c = hessenberg_(k + 1, k);
      const double radius = std::hypot(a, c);
      cos_[k] = radius > 0 ? a / radius : 1.0;
      sin_[k] = radius > 0 ? c / radius : 0.0;
      hessenberg_(k, k) = radius;
      hessenberg_(k + 1, k) = 0;
      rhs_[k + 1] = -sin_[k] * rhs_[k];
      rhs_[k] = cos_[k] * rhs_[k];
      residual = std::abs(rhs_[k + 1]);
      ++k;
      if (h_next == 0) break;  // lucky breakdown: the Krylov space holds the solution
      basis_.col(k) = w_ / h_next;
    }
    // x += V_k y with H_k y = rhs_k (upper triangular after the rotations).
    auto y = y_.head(k);
    for (Index i = k - 1; i >= 0; --i) {
      double sum = rhs_[i];
      for (Index j = i + 1; j < k; ++j) sum -= hessenberg_(i, j) * y[j];
      if (hessenberg_(i, i) == 0) return result;  // singular operator
      y[i] = sum / hessenberg_(i, i);
    }
    x.noalias() += basis_.leftCols(k) * y;
    // The true residual for the restart (the recurrence's estimate drifts in round-off).
    apply(x, w_);
    ++result.iterations;
    r_ = b - w_;
    if (!r_.allFinite()) return result;
  }
  result.relative_residual = r_.norm() / b_norm;
  result.converged = result.relative_residual <= options_.relative_tolerance;
  return result;
}

}  // namespace gipsi
