#include "gipsi/numerics/ode.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {

bool OdeIntegrator::Step(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) {
  GIPSI_CHECK(prepared_size_ == system.size(), "{}: Prepare({}) but system size {}", name(),
              prepared_size_, system.size());
  GIPSI_CHECK(x.size() == system.size(), "state size {} != system size {}", x.size(),
              system.size());
  GIPSI_CHECK(dt > 0, "dt must be positive, got {}", dt);
  GIPSI_CHECK(!needs_second_order() ||
                  (system.num_positions() > 0 && 2 * system.num_positions() == system.size()),
              "{} needs a mechanical system (x = [q; v])", name());
  failure_.clear();
  return DoStep(system, t, dt, x);
}

void ExplicitEuler::DoPrepare(Index n) { k_.resize(n); }

bool ExplicitEuler::DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) {
  system.CalcDerivative(t, x, k_);
  x.noalias() += dt * k_;
  return true;
}

void SymplecticEuler::DoPrepare(Index n) { k_.resize(n); }

bool SymplecticEuler::DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) {
  const Index n = system.num_positions();
  system.CalcDerivative(t, x, k_);
  // k_ = [v; a(q, v)]: update velocities first, then positions with the new velocities.
  x.tail(n).noalias() += dt * k_.tail(n);
  x.head(n).noalias() += dt * x.tail(n);
  return true;
}

void RungeKutta4::DoPrepare(Index n) {
  k1_.resize(n);
  k2_.resize(n);
  k3_.resize(n);
  k4_.resize(n);
  tmp_.resize(n);
}

bool RungeKutta4::DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) {
  const double h2 = 0.5 * dt;
  system.CalcDerivative(t, x, k1_);
  tmp_.noalias() = x + h2 * k1_;
  system.CalcDerivative(t + h2, tmp_, k2_);
  tmp_.noalias() = x + h2 * k2_;
  system.CalcDerivative(t + h2, tmp_, k3_);
  tmp_.noalias() = x + dt * k3_;
  system.CalcDerivative(t + dt, tmp_, k4_);
  x.noalias() += (dt / 6.0) * (k1_ + 2.0 * k2_ + 2.0 * k3_ + k4_);
  return true;
}

void BackwardEulerOde::DoPrepare(Index n) {
  for (VecX* v : {&y_, &f_, &f0_, &g_, &delta_, &y_probe_, &f_probe_}) v->setZero(n);
  gmres_.Prepare(n, options_.linear);
}

bool BackwardEulerOde::DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) {
  const double t1 = t + dt;
  newton_iterations_ = linear_iterations_ = 0;
  system.CalcDerivative(t, x, f0_);
  if (!f0_.allFinite()) {
    failure_ = "the derivative is not finite at the start of the step";
    return false;
  }
  y_.noalias() = x + dt * f0_;  // explicit Euler predictor: O(dt²) from the solution
  // (I − dt ∂f/∂y) w by a forward difference of f around the current iterate (f_ = f(t1, y_)),
  // with the step of Knoll & Keyes (2004), eq. (11): √ε_mach (1 + ‖y‖) / ‖w‖.
  double y_norm = 0;
  auto apply = [&](Eigen::Ref<const VecX> w, Eigen::Ref<VecX> out) {
    const double w_norm = w.norm();
    if (w_norm == 0) {
      out.setZero();
      return;
    }
    const double h = std::sqrt(std::numeric_limits<double>::epsilon()) * (1 + y_norm) / w_norm;
    y_probe_.noalias() = y_ + h * w;
    system.CalcDerivative(t1, y_probe_, f_probe_);
    out.noalias() = w - (dt / h) * (f_probe_ - f_);
  };
  const LinearOperatorRef op(apply);
  for (int iteration = 0; iteration < options_.max_newton_iterations; ++iteration) {
    system.CalcDerivative(t1, y_, f_);
    if (!f_.allFinite()) {
      failure_ = fmt::format("the derivative is not finite at Newton iterate {}", iteration);
      return false;
    }
    g_.noalias() = x + dt * f_ - y_;  // −G(y): the right-hand side of the Newton system
    y_norm = y_.norm();
    const GmresResult linear = gmres_.Solve(op, g_, delta_);
    linear_iterations_ += linear.iterations;
    if (!delta_.allFinite() || !(linear.relative_residual < 1)) {
      failure_ = fmt::format(
          "GMRES made no progress on Newton iteration {} (relative residual {:.3g} after {} "
          "products)",
          iteration, linear.relative_residual, linear.iterations);
      return false;
    }
    // One scale per block (positions and velocities of a mechanical system, else the whole
    // state): components that are exactly zero (a fixed node, a planar motion) are judged
    // against the size of their block, not against nothing. A velocity error δv moves the
    // positions by Δt δv, so velocities are also converged once that is within the positions'
    // tolerance (at rest the velocities are ~0 and their own size is below rounding).
    const Index np = system.num_positions();
    const bool mechanical = np > 0 && 2 * np == x.size();
    auto block_size = [&](Index begin, Index size) {
      return std::max({x.segment(begin, size).lpNorm<Eigen::Infinity>(),
                       y_.segment(begin, size).lpNorm<Eigen::Infinity>(),
                       dt * f0_.segment(begin, size).lpNorm<Eigen::Infinity>()});
    };
    bool converged;
    if (mechanical) {
      const double tol_q = options_.relative_tolerance * block_size(0, np);
      const double tol_v = std::max(options_.relative_tolerance * block_size(np, np), tol_q / dt);
      converged =
          delta_.head(np).lpNorm<Eigen::Infinity>() <= tol_q + options_.absolute_tolerance &&
          delta_.tail(np).lpNorm<Eigen::Infinity>() <= tol_v + options_.absolute_tolerance;
    } else {
      converged =
          delta_.lpNorm<Eigen::Infinity>() <=
          options_.relative_tolerance * block_size(0, x.size()) + options_.absolute_tolerance;
    }
    y_ += delta_;
    ++newton_iterations_;
    if (converged) {
      x = y_;
      return true;
    }
  }
  failure_ = fmt::format("Newton did not converge in {} iterations (last update {:.3g})",
                         options_.max_newton_iterations, delta_.lpNorm<Eigen::Infinity>());
  return false;
}

}  // namespace gipsi
