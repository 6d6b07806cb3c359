#pragma once
/// @file
/// The contract between modeling tools and time integrators. A model that wants to be stepped
/// by an explicit integrator states its ODE dx/dt = f(t, x); the integrator never knows the
/// physics. Mechanical models say that the first `num_positions` entries of x are positions q
/// and the next `num_positions` are their velocities v (so dq/dt = v), which lets symplectic
/// integrators split the update.

#include <concepts>
#include <string_view>

#include "gipsi/base/math.h"

namespace gipsi {

/// Any type with a state size, a position count (0 for a general ODE) and a derivative.
/// `CalcDerivative(t, x, xdot)` writes f(t, x) into xdot (both of size `ode_size()`) and must
/// not allocate.
template <class S>
concept OdeSystem = requires(const S& s, double t, Eigen::Ref<const VecX> x,
                             Eigen::Ref<VecX> xdot) {
  { s.ode_size() } -> std::convertible_to<Index>;
  { s.ode_num_positions() } -> std::convertible_to<Index>;
  s.CalcDerivative(t, x, xdot);
};

/// A non-owning, type-erased view of an OdeSystem, so integrators can be chosen at run time by
/// name. Trivially copyable; the viewed system must outlive the view.
class OdeView {
 public:
  template <OdeSystem S>
  explicit OdeView(const S& system)
      : system_(&system),
        size_(system.ode_size()),
        num_positions_(system.ode_num_positions()),
        derivative_([](const void* s, double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) {
          static_cast<const S*>(s)->CalcDerivative(t, x, xdot);
        }) {}

  [[nodiscard]] Index size() const { return size_; }
  [[nodiscard]] Index num_positions() const { return num_positions_; }
  void CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
    derivative_(system_, t, x, xdot);
  }

 private:
  const void* system_;
  Index size_;
  Index num_positions_;
  void (*derivative_)(const void*, double, Eigen::Ref<const VecX>, Eigen::Ref<VecX>);
};

/// An explicit one-step integrator. Not copyable (holds work buffers); movable.
/// Usage: `Prepare(n)` once, then `Step` every step; Step allocates nothing.
class ExplicitIntegrator {
 public:
  ExplicitIntegrator() = default;
  ExplicitIntegrator(const ExplicitIntegrator&) = delete;
  ExplicitIntegrator& operator=(const ExplicitIntegrator&) = delete;
  ExplicitIntegrator(ExplicitIntegrator&&) = default;
  ExplicitIntegrator& operator=(ExplicitIntegrator&&) = default;
  virtual ~ExplicitIntegrator() = default;

  /// Registry name, e.g. "RK4".
  [[nodiscard]] virtual std::string_view name() const = 0;
  /// Global order of accuracy.
  [[nodiscard]] virtual int order() const = 0;
  /// True if the method needs a mechanical (q, v) split (num_positions > 0, size == 2·q).
  [[nodiscard]] virtual bool needs_second_order() const { return false; }

  /// Allocates work space for systems of size `n`.
  void Prepare(Index n) {
    prepared_size_ = n;
    DoPrepare(n);
  }
  /// Advances `x` (size n) from time t to t + dt. Preconditions (checked): Prepare(n) was
  /// called with n == system.size(); dt > 0; for second-order methods, the system is mechanical.
  void Step(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x);

 protected:
  virtual void DoPrepare(Index n) = 0;
  virtual void DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) = 0;

 private:
  Index prepared_size_ = -1;
};

/// Forward (explicit) Euler: x += dt f(t, x). First order.
class ExplicitEuler final : public ExplicitIntegrator {
 public:
  [[nodiscard]] std::string_view name() const override { return "ExplicitEuler"; }
  [[nodiscard]] int order() const override { return 1; }

 protected:
  void DoPrepare(Index n) override;
  void DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) override;

 private:
  VecX k_;
};

/// Semi-implicit (symplectic) Euler for mechanical systems: v += dt a(t, q, v); q += dt v.
/// First order; keeps the energy of Hamiltonian systems bounded (no secular drift).
class SymplecticEuler final : public ExplicitIntegrator {
 public:
  [[nodiscard]] std::string_view name() const override { return "SymplecticEuler"; }
  [[nodiscard]] int order() const override { return 1; }
  [[nodiscard]] bool needs_second_order() const override { return true; }

 protected:
  void DoPrepare(Index n) override;
  void DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) override;

 private:
  VecX k_;
};

/// The classic fourth-order Runge–Kutta method.
class RungeKutta4 final : public ExplicitIntegrator {
 public:
  [[nodiscard]] std::string_view name() const override { return "RK4"; }
  [[nodiscard]] int order() const override { return 4; }

 protected:
  void DoPrepare(Index n) override;
  void DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) override;

 private:
  VecX k1_, k2_, k3_, k4_, tmp_;
};

}  // namespace gipsi
