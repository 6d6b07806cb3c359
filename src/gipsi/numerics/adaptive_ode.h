#pragma once
/// @file
/// Adaptive explicit integration with error control, dense output and event location: the
/// Dormand–Prince 5(4) embedded Runge–Kutta pair (Dormand & Prince, J. Comput. Appl. Math.
/// 6:19–26, 1980) with its fourth-order continuous extension (Shampine, Math. Comp. 46:135–150,
/// 1986; Hairer, Nørsett & Wanner, Solving ODEs I, 2nd ed., §II.6). Events are zero crossings of
/// user functions g(t, x), located by root finding on the dense output to a tolerance in time.
/// This is the computational tool for hybrid systems (GiPSi's valves): the caller changes its
/// mode at the event and restarts the integration there.
///
/// Error control: a step is accepted when the RMS norm of the embedded error estimate, each
/// component divided by atol_i + rtol·max(|x_i|, |x̃_i|), is at most 1; the next step is
/// h·min(5, max(0.2, 0.9·err^(−1/5))) (no growth right after a rejection).

#include <cstdint>
#include <limits>

#include "gipsi/base/math.h"
#include "gipsi/numerics/ode.h"

namespace gipsi {

class StateReader;
class StateWriter;

/// Event functions for AdaptiveOde: `num_events()` values g_i(t, x); event i happens where g_i
/// crosses zero upward (from ≤ 0 to > 0). A caller that wants a downward crossing negates its
/// function. `Calc` must not allocate. Interface only (not copyable through the base).
class EventFunctions {
 public:
  virtual ~EventFunctions() = default;
  [[nodiscard]] virtual int num_events() const = 0;
  /// Writes g(t, x) (size num_events()) into `g`.
  virtual void Calc(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> g) const = 0;
};

/// Tolerances and limits of AdaptiveOde. Plain configuration; copyable.
struct AdaptiveOdeOptions {
  double relative_tolerance = 1e-6;  ///< rtol, > 0
  /// Absolute tolerance of every component (used when `absolute_tolerances` is empty), > 0.
  double absolute_tolerance = 1e-9;
  VecX absolute_tolerances;  ///< per-component atol_i (size n), or empty
  double max_step = std::numeric_limits<double>::infinity();  ///< largest step, > 0
  /// First step of the first Integrate call; 0 chooses it from the problem's scales.
  double initial_step = 0;
  /// A step shorter than min_step_factor·max(|t|, 1) means the problem is too stiff or singular.
  double min_step_factor = 1e-13;
  std::int64_t max_steps = 10'000'000;  ///< attempted steps per Integrate call
  double event_tolerance = 1e-10;       ///< events are located to this width in time, > 0
  int event_samples = 4;  ///< sign checks per step: at θ = k/event_samples, k = 1..event_samples
};

/// How an Integrate call ended. Plain struct.
struct AdaptiveOdeResult {
  enum class Outcome : std::uint8_t {
    kReachedEnd,    ///< t == t_end
    kEvent,         ///< stopped at event `event` (t is the located time)
    kStepTooSmall,  ///< the controller asked for a step below the minimum
    kTooManySteps,  ///< max_steps attempts without reaching t_end
    kNonFinite,     ///< a derivative or the error estimate was not finite
  };
  Outcome outcome = Outcome::kReachedEnd;
  int event = -1;                ///< index of the event function, for kEvent
  std::int64_t accepted = 0;     ///< accepted steps in this call
  std::int64_t rejected = 0;     ///< rejected steps in this call
  std::int64_t evaluations = 0;  ///< derivative evaluations in this call
  [[nodiscard]] bool ok() const {
    return outcome == Outcome::kReachedEnd || outcome == Outcome::kEvent;
  }
};

/// Dormand–Prince 5(4) with dense output and event location. Not copyable (work buffers);
/// movable. Usage: `Prepare(n, m)` once; then `Integrate` as often as needed. The last step size
/// is kept as the first guess of the next call. Integrate allocates nothing.
class AdaptiveOde {
 public:
  AdaptiveOde() = default;
  AdaptiveOde(const AdaptiveOde&) = delete;
  AdaptiveOde& operator=(const AdaptiveOde&) = delete;
  AdaptiveOde(AdaptiveOde&&) = default;
  AdaptiveOde& operator=(AdaptiveOde&&) = default;

  /// Method order (of the propagated solution) and of the dense output.
  static constexpr int kOrder = 5;
  static constexpr int kDenseOrder = 4;

  /// Sizes the work buffers for systems of size `n` with up to `num_events` event functions,
  /// and sets the options. Preconditions (checked): n ≥ 1, tolerances > 0, absolute_tolerances
  /// empty or of size n.
  void Prepare(Index n, int num_events, const AdaptiveOdeOptions& options);
  [[nodiscard]] const AdaptiveOdeOptions& options() const { return options_; }

  /// Integrates dx/dt = f(t, x) from `t` to `t_end` > t, updating `t` and `x` (size n) in place.
  /// With `events`, stops at the first upward zero crossing of any g_i: then `t` is the located
  /// time (to options().event_tolerance, on the side where g_i > 0) and `x` the dense output
  /// there. Only crossings inside the interval count: a g_i already > 0 at the start is not
  /// reported (see FirstPositive; hybrid callers keep every g_i ≤ 0 in their current mode).
  /// On failure `t` and `x` hold the last accepted state. Never throws.
  AdaptiveOdeResult Integrate(const OdeView& system, double& t, double t_end, Eigen::Ref<VecX> x,
                              const EventFunctions* events = nullptr);

  /// The first i with g_i(t, x) > 0, or −1: an event pending at (t, x). Allocates nothing
  /// (after Prepare).
  int FirstPositive(const EventFunctions& events, double t, Eigen::Ref<const VecX> x);

  /// The dense output of the last accepted step at time `s` in [step_begin(), step_end()]
  /// (fourth order). After an event the step still covers its whole attempted length (the
  /// event time lies inside it). Precondition: a step has been accepted.
  void Interpolate(double s, Eigen::Ref<VecX> out) const;
  [[nodiscard]] double step_begin() const { return t_old_; }
  [[nodiscard]] double step_end() const { return t_old_ + h_old_; }
  /// The step size the controller proposes next (0 before the first step).
  [[nodiscard]] double next_step() const { return h_; }
  /// Forgets the step-size guess (e.g. after a discontinuity in the model).
  void ResetStepSize() { h_ = 0; }
  /// Sets the step-size guess (0: choose one): a second integrator started like this one
  /// repeats its steps exactly (trial integrations).
  void SetStepSize(double h) { h_ = h; }
  /// Checkpoints (gipsi/base/state.h; defined in circulation_state.cc).
  void SaveState(StateWriter& out) const;
  void RestoreState(StateReader& in);

 private:
  double InitialStep(const OdeView& system, double t, double t_end, const VecX& x);
  double ErrorNorm(const VecX& x, const VecX& x_new) const;
  // Dense output at fraction θ of the last accepted step into `out`.
  void DenseAt(double theta, Eigen::Ref<VecX> out) const;
  // Root of g_i between fractions a < b of the last step with g_i(a) ≤ 0 < g_i(b); returns the
  // fraction on the positive side.
  double LocateRoot(const EventFunctions& events, int i, double a, double ga, double b, double gb);

  AdaptiveOdeOptions options_;
  VecX atol_;
  VecX k_[7];
  VecX x_old_, x_new_, stage_, err_;
  VecX g_old_, g_new_, g_probe_, g_prev_, g_right_;
  VecX dense_;
  double t_old_ = 0, h_old_ = 0;
  double h_ = 0;
  bool have_step_ = false;
  Index n_ = 0;
};

}  // namespace gipsi
