#pragma once
/// @file
/// The contract between modeling tools and time integrators. A model that wants to be stepped
/// by an explicit integrator states its ODE dx/dt = f(t, x); the integrator never knows the
/// physics. Mechanical models say that the first `num_positions` entries of x are positions q
/// and the next `num_positions` are their velocities v (so dq/dt = v), which lets symplectic
/// integrators split the update.

#include <concepts>
#include <string>
#include <string_view>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/numerics/gmres.h"

GIPSI_EXPORT_BEGIN
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

/// A one-step integrator of an OdeSystem, explicit or implicit: any object that states its ODE
/// can be stepped by any of them (chosen by name in the scene, registry "integrator" table).
/// Not copyable (holds work buffers); movable. Usage: `Prepare(n)` once, then `Step` every
/// step; Step allocates nothing.
class OdeIntegrator {
 public:
  OdeIntegrator() = default;
  OdeIntegrator(const OdeIntegrator&) = delete;
  OdeIntegrator& operator=(const OdeIntegrator&) = delete;
  OdeIntegrator(OdeIntegrator&&) = default;
  OdeIntegrator& operator=(OdeIntegrator&&) = default;
  virtual ~OdeIntegrator() = default;

  /// Registry name, e.g. "RK4".
  [[nodiscard]] virtual std::string_view name() const = 0;
  /// Global order of accuracy.
  [[nodiscard]] virtual int order() const = 0;
  /// True if the method needs a mechanical (q, v) split (num_positions > 0, size == 2·q).
  [[nodiscard]] virtual bool needs_second_order() const { return false; }
  /// False for implicit methods, which have no step-size limit for stability.
  [[nodiscard]] virtual bool is_explicit() const { return true; }

  /// Allocates work space for systems of size `n`.
  void Prepare(Index n) {
    prepared_size_ = n;
    DoPrepare(n);
  }
  /// Advances `x` (size n) from time t to t + dt. Preconditions (checked): Prepare(n) was
  /// called with n == system.size(); dt > 0; for second-order methods, the system is mechanical.
  /// Returns false, leaving `x` unchanged, if an implicit method's solve failed (failure() says
  /// why); explicit methods always return true (a too-large step shows in the state).
  bool Step(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x);
  /// Why the last Step returned false.
  [[nodiscard]] const std::string& failure() const { return failure_; }

 protected:
  virtual void DoPrepare(Index n) = 0;
  virtual bool DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) = 0;
  std::string failure_;

 private:
  Index prepared_size_ = -1;
};

/// Forward (explicit) Euler: x += dt f(t, x). First order.
class ExplicitEuler final : public OdeIntegrator {
 public:
  [[nodiscard]] std::string_view name() const override { return "ExplicitEuler"; }
  [[nodiscard]] int order() const override { return 1; }

 protected:
  void DoPrepare(Index n) override;
  bool DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) override;

 private:
  VecX k_;
};

/// Semi-implicit (symplectic) Euler for mechanical systems: v += dt a(t, q, v); q += dt v.
/// First order; keeps the energy of Hamiltonian systems bounded (no secular drift).
class SymplecticEuler final : public OdeIntegrator {
 public:
  [[nodiscard]] std::string_view name() const override { return "SymplecticEuler"; }
  [[nodiscard]] int order() const override { return 1; }
  [[nodiscard]] bool needs_second_order() const override { return true; }

 protected:
  void DoPrepare(Index n) override;
  bool DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) override;

 private:
  VecX k_;
};

/// The classic fourth-order Runge–Kutta method.
class RungeKutta4 final : public OdeIntegrator {
 public:
  [[nodiscard]] std::string_view name() const override { return "RK4"; }
  [[nodiscard]] int order() const override { return 4; }

 protected:
  void DoPrepare(Index n) override;
  bool DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) override;

 private:
  VecX k1_, k2_, k3_, k4_, tmp_;
};

/// Backward (implicit) Euler, x_{n+1} = x_n + Δt f(t_{n+1}, x_{n+1}). First order, L-stable:
/// no step-size limit for stability, and stiff modes are damped rather than amplified. The
/// nonlinear equation is solved by an inexact Newton method whose linear systems
/// (I − Δt ∂f/∂x) δ = −G are solved by GMRES with Jacobian-vector products by finite
/// differences of f (Knoll & Keyes, J. Comput. Phys. 193:357–397, 2004), so the model provides
/// nothing but its derivative. Each Newton iteration costs one evaluation of f per GMRES
/// iteration, and GMRES needs more iterations as Δt·‖∂f/∂x‖ grows (there is no preconditioner):
/// it suits moderate stiffness (a mass-spring network a few times beyond its explicit limit),
/// not a large stiff FEM solve (FemSolid's implicit schemes assemble and factorise instead).
/// Converged when the last Newton update is within relative_tolerance · max(‖x_n‖∞,
/// ‖x_{n+1}‖∞, Δt ‖f(t_n, x_n)‖∞) + absolute_tolerance, taken per block (positions and
/// velocities of a mechanical system separately, else the whole state); a velocity update
/// also passes when Δt times it is within the positions' tolerance.
class BackwardEulerOde final : public OdeIntegrator {
 public:
  struct Options {
    double relative_tolerance = 1e-10;
    double absolute_tolerance = 1e-300;
    int max_newton_iterations = 20;
    GmresOptions linear{30, 600, 1e-8};
  };
  BackwardEulerOde() = default;
  explicit BackwardEulerOde(Options options) : options_(options) {}

  [[nodiscard]] std::string_view name() const override { return "BackwardEuler"; }
  [[nodiscard]] int order() const override { return 1; }
  [[nodiscard]] bool is_explicit() const override { return false; }
  /// Newton and GMRES iterations of the last step.
  [[nodiscard]] int last_newton_iterations() const { return newton_iterations_; }
  [[nodiscard]] int last_linear_iterations() const { return linear_iterations_; }

 protected:
  void DoPrepare(Index n) override;
  bool DoStep(const OdeView& system, double t, double dt, Eigen::Ref<VecX> x) override;

 private:
  Options options_;
  Gmres gmres_;
  VecX y_, f_, f0_, g_, delta_, y_probe_, f_probe_;
  int newton_iterations_ = 0, linear_iterations_ = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
