#include "gipsi/numerics/ode.h"

#include "gipsi/base/error.h"

namespace gipsi {

void ExplicitIntegrator::Step(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) {
  GIPSI_CHECK(prepared_size_ == system.size(), "{}: Prepare({}) but system size {}", name(),
              prepared_size_, system.size());
  GIPSI_CHECK(x.size() == system.size(), "state size {} != system size {}", x.size(),
              system.size());
  GIPSI_CHECK(dt > 0, "dt must be positive, got {}", dt);
  GIPSI_CHECK(!needs_second_order() ||
                  (system.num_positions() > 0 && 2 * system.num_positions() == system.size()),
              "{} needs a mechanical system (x = [q; v])", name());
  DoStep(system, t, dt, x);
}

void ExplicitEuler::DoPrepare(Index n) { k_.resize(n); }

void ExplicitEuler::DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) {
  system.CalcDerivative(t, x, k_);
  x.noalias() += dt * k_;
}

void SymplecticEuler::DoPrepare(Index n) { k_.resize(n); }

void SymplecticEuler::DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) {
  const Index n = system.num_positions();
  system.CalcDerivative(t, x, k_);
  // k_ = [v; a(q, v)]: update velocities first, then positions with the new velocities.
  x.tail(n).noalias() += dt * k_.tail(n);
  x.head(n).noalias() += dt * x.tail(n);
}

void RungeKutta4::DoPrepare(Index n) {
  k1_.resize(n);
  k2_.resize(n);
  k3_.resize(n);
  k4_.resize(n);
  tmp_.resize(n);
}

void RungeKutta4::DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) {
  const double h2 = 0.5 * dt;
  system.CalcDerivative(t, x, k1_);
  tmp_.noalias() = x + h2 * k1_;
  system.CalcDerivative(t + h2, tmp_, k2_);
  tmp_.noalias() = x + h2 * k2_;
  system.CalcDerivative(t + h2, tmp_, k3_);
  tmp_.noalias() = x + dt * k3_;
  system.CalcDerivative(t + dt, tmp_, k4_);
  x.noalias() += (dt / 6.0) * (k1_ + 2.0 * k2_ + 2.0 * k3_ + k4_);
}

}  // namespace gipsi
