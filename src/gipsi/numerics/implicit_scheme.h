#pragma once
/// @file
/// Implicit time-stepping schemes for second-order (mechanical) systems
///     M a + C v + f_int(x) = f_ext(x),
/// written so that any of them reduces a step to one nonlinear solve for the displacement
/// increment d = x_{n+1} − x_n: every scheme makes the new velocity and acceleration affine in d,
///     v_{n+1} = c_v d + v̂,   a_{n+1} = c_a d + â,
/// so the residual is r(d) = M (c_a d + â) + C (c_v d + v̂) + f_int − f_ext and its Jacobian is
/// c_a M + c_v C + K. Schemes:
///  - Static:        c_a = c_v = 0 (quasi-static equilibrium; v = a = 0).
///  - BackwardEuler: v = d/Δt, a = (v − v_n)/Δt. First order, strongly damped (L-stable).
///  - BDF2:          v = (3 x_{n+1} − 4 x_n + x_{n−1})/(2Δt), a likewise from velocities.
///                   Second order, L-stable; falls back to backward Euler for the first step and
///                   whenever the step size changed.
///  - Newmark:       x_{n+1} = x_n + Δt v_n + Δt²((½ − β) a_n + β a_{n+1}),
///                   v_{n+1} = v_n + Δt((1 − γ) a_n + γ a_{n+1}); β = ¼, γ = ½ (average
///                   acceleration) is second order and conserves the energy of linear systems.
///                   (N. M. Newmark, J. Eng. Mech. Div. ASCE 85(3):67–94, 1959.)

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/base/state_value.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class StateReader;
class StateWriter;

enum class ImplicitSchemeKind { kStatic, kBackwardEuler, kBdf2, kNewmark };

/// Every kind, in the order messages list them.
inline constexpr std::array<ImplicitSchemeKind, 4> kImplicitSchemeKinds = {
    ImplicitSchemeKind::kStatic, ImplicitSchemeKind::kBackwardEuler, ImplicitSchemeKind::kBdf2,
    ImplicitSchemeKind::kNewmark};

/// Name used in scene files: "Static", "BackwardEuler", "BDF2", "Newmark".
std::string_view ToString(ImplicitSchemeKind kind);
/// The kind a scene file names (ToString's name), or nullopt for any other name.
std::optional<ImplicitSchemeKind> ImplicitSchemeNamed(std::string_view name);

/// Scheme state: the history it needs (x_n, v_n, a_n, x_n − x_{n−1}, v_{n−1}). Copyable (for
/// rolling back a failed step); allocation-free after `Reset`.
class ImplicitScheme {
 public:
  ImplicitScheme() = default;
  ImplicitScheme(ImplicitSchemeKind kind, double newmark_beta = 0.25, double newmark_gamma = 0.5);

  [[nodiscard]] ImplicitSchemeKind kind() const { return kind_; }
  /// Order of accuracy in time (0 for Static).
  [[nodiscard]] int order() const;

  /// Starts from positions x (3N), velocities v and accelerations a; forgets older history.
  void Reset(const VecX& x, const VecX& v, const VecX& a);
  /// Prepares a step of size dt > 0: sets c_a, c_v, â, v̂ (allocation-free).
  void Begin(double dt);
  [[nodiscard]] double c_a() const { return c_a_; }
  [[nodiscard]] double c_v() const { return c_v_; }
  [[nodiscard]] const VecX& a_hat() const { return a_hat_; }
  [[nodiscard]] const VecX& v_hat() const { return v_hat_; }
  /// The increment that gives velocity `v_target` on one degree of freedom (velocity-driven
  /// boundary conditions); for Static, dt · v_target.
  [[nodiscard]] double IncrementForVelocity(Index dof, double v_target) const;
  /// Accepts the step with increment d: updates x_n, v_n, a_n and the history.
  void Commit(const VecX& d);

  [[nodiscard]] const VecX& x() const { return x_; }
  [[nodiscard]] const VecX& v() const { return v_; }
  [[nodiscard]] const VecX& a() const { return a_; }
  /// Overwrites the current velocities (a field write); drops multistep history.
  void SetVelocity(const VecX& v);
  /// Overwrites the current positions (a field write); drops multistep history.
  void SetPositions(const VecX& x);
  /// Overwrites the current accelerations (Newmark's initial a_0).
  void SetAcceleration(const VecX& a) { a_ = a; }
  /// State value fields (gipsi/base/state_value.h): the kind (checked on reading), the state
  /// and the multistep history. The per-step coefficients (c_a, c_v, a_hat, v_hat) are not
  /// state: Begin rebuilds them.
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("kind", s.kind_, Shape::kFixed);
    v("x", s.x_, Shape::kFixed);
    v("v", s.v_, Shape::kFixed);
    v("a", s.a_);
    v("dx_prev", s.dx_prev_);
    v("v_prev", s.v_prev_);
    v("dt_prev", s.dt_prev_);
    v("dt", s.dt_);
    v("bdf2_now", s.bdf2_now_);
  }

 private:
  ImplicitSchemeKind kind_ = ImplicitSchemeKind::kBackwardEuler;
  double beta_ = 0.25, gamma_ = 0.5;
  VecX x_, v_, a_;
  VecX dx_prev_, v_prev_;  // x_n − x_{n−1}, v_{n−1}
  double dt_prev_ = 0;     // 0: no usable history
  double dt_ = 0;
  bool bdf2_now_ = false;
  double c_a_ = 0, c_v_ = 0;
  VecX a_hat_, v_hat_;
};

/// Where a dynamic step's nonlinear solve starts (the solids' scene key "predictor"):
/// - kNone: at x_n (increment 0);
/// - kConstantVelocity: at x_n + h v_n; for smooth motion the first iterate is then O(h² a)
///   from the solution instead of O(h v);
/// - kConstantAcceleration: at the increment the scheme turns into the velocity v_n + h a_n
///   (x_n + h v_n + h² a_n for backward Euler), O(h³ ȧ) from the solution.
enum class StepPredictor : std::uint8_t { kNone, kConstantVelocity, kConstantAcceleration };

/// The predicted increment d of a step of length h, after scheme.Begin(h) (kNone: zero, d's size
/// kept; otherwise sized as scheme.v()).
void PredictIncrement(const ImplicitScheme& scheme, StepPredictor predictor, double h, VecX& d);

}  // namespace gipsi
GIPSI_EXPORT_END
