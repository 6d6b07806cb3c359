#pragma once
/// @file
/// Restarted GMRES(m) for a linear operator given only as a product y = A x (matrix-free):
/// Saad & Schultz, SIAM J. Sci. Stat. Comput. 7:856–869, 1986; Saad, Iterative Methods for
/// Sparse Linear Systems, 2nd ed., §6.5 (Arnoldi with modified Gram–Schmidt, Givens rotations
/// on the Hessenberg matrix, so the residual norm is known at every iteration without forming
/// the iterate). No preconditioner: the callers' operators are close to the identity (an
/// implicit step's I − h ∂f/∂x at moderate h·‖∂f/∂x‖).

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Options of Gmres. Plain struct.
struct GmresOptions {
  int restart = 30;                   ///< Krylov dimension m before a restart, ≥ 1
  int max_iterations = 300;           ///< operator products over all restarts, ≥ 1
  double relative_tolerance = 1e-10;  ///< stop when ‖b − A x‖ ≤ this · ‖b‖
};

/// How a solve ended. Plain struct.
struct GmresResult {
  bool converged = false;
  int iterations = 0;            ///< operator products
  double relative_residual = 0;  ///< ‖b − A x‖ / ‖b‖ (the recurrence's estimate)
};

/// A non-owning view of a callable `apply(x, y)` that writes A x into y (both of size n; they
/// never alias). Trivially copyable, allocation-free; the callable must outlive the view.
class LinearOperatorRef {
 public:
  template <class F>
  explicit LinearOperatorRef(F& apply)
      : object_(&apply), call_([](void* o, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> y) {
          (*static_cast<F*>(o))(x, y);
        }) {}
  void operator()(Eigen::Ref<const VecX> x, Eigen::Ref<VecX> y) const { call_(object_, x, y); }

 private:
  void* object_;
  void (*call_)(void*, Eigen::Ref<const VecX>, Eigen::Ref<VecX>);
};

/// Restarted GMRES with preallocated work space. Not copyable (work space); movable.
class Gmres {
 public:
  using Operator = LinearOperatorRef;

  Gmres() = default;
  Gmres(const Gmres&) = delete;
  Gmres& operator=(const Gmres&) = delete;
  Gmres(Gmres&&) = default;
  Gmres& operator=(Gmres&&) = default;

  /// Sizes the work space for systems of size n. Preconditions (checked): n ≥ 1, restart ≥ 1,
  /// max_iterations ≥ 1, relative_tolerance > 0.
  void Prepare(Index n, const GmresOptions& options);
  /// Solves A x = b starting from x = 0 (x is overwritten). Allocates nothing after Prepare.
  GmresResult Solve(const Operator& apply, const VecX& b, VecX& x);

 private:
  GmresOptions options_;
  Eigen::MatrixXd basis_;       // n by m + 1: the Arnoldi vectors
  Eigen::MatrixXd hessenberg_;  // m + 1 by m, rotated to upper triangular as it grows
  VecX cos_, sin_, rhs_;        // Givens rotations and the rotated right-hand side (m + 1)
  VecX w_, r_, y_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
