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

#include <array>
#include <cstdint>
#include <limits>
#include <string_view>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/base/state_value.h"
#include "gipsi/numerics/ode.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

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

/// What AdaptiveOde carries from one Integrate call to the next, as a state value type
/// (gipsi/base/state_value.h): the step size the controller proposes next, and the last accepted
/// step (start, length, initial value and stages), which is its dense output. Everything else
/// in AdaptiveOde is work space, rewritten before it is read. A caller that integrates several
/// trajectories with one AdaptiveOde (a trial integration beside the real one) keeps one state
/// each and passes it to Integrate. Copyable.
struct AdaptiveOdeState {
  double next_step = 0;         ///< the controller's next step size; 0: choose one
  bool have_step = false;       ///< a step was accepted: the dense output below is valid
  double t_old = 0, h_old = 0;  ///< start and length of the last accepted step
  VecX x_old;                   ///< x at its start
  std::array<VecX, 7> k;        ///< its stages; k[6] = f at its end (first stage of the next)

  template <class Self, class Visitor>
  static void Fields(Self& s, Visitor& v) {
    static constexpr std::array<std::string_view, 7> kStages = {"k1", "k2", "k3", "k4",
                                                                "k5", "k6", "k7"};
    v("next_step", s.next_step);
    v("have_step", s.have_step);
    v("t_old", s.t_old);
    v("h_old", s.h_old);
    v("x_old", s.x_old, Shape::kFixed);
    for (std::size_t i = 0; i < kStages.size(); ++i) v(kStages[i], s.k[i], Shape::kFixed);
  }
};

/// Dormand–Prince 5(4) with dense output and event location. Not copyable (work buffers);
/// movable. Usage: `Prepare(n, m)` once; then `Integrate` as often as needed. The last step size
/// is kept as the first guess of the next call (in the AdaptiveOdeState integrated: the
/// object's own, or one the caller keeps). Integrate allocates nothing.
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
                              const EventFunctions* events = nullptr) {
    return Integrate(state_, system, t, t_end, x, events);
  }
  /// The same, continuing from (and updating) the caller's `memory` instead of the object's own
  /// state: `memory` must come from NewState() of an AdaptiveOde prepared for the same size.
  AdaptiveOdeResult Integrate(AdaptiveOdeState& memory, const OdeView& system, double& t,
                              double t_end, Eigen::Ref<VecX> x,
                              const EventFunctions* events = nullptr);
  /// A fresh state sized for this integrator (no step taken, the options' initial step).
  [[nodiscard]] AdaptiveOdeState NewState() const;
  /// The object's own state (what the one-argument Integrate continues from).
  [[nodiscard]] const AdaptiveOdeState& state() const { return state_; }

  /// The first i with g_i(t, x) > 0, or −1: an event pending at (t, x). Allocates nothing
  /// (after Prepare).
  int FirstPositive(const EventFunctions& events, double t, Eigen::Ref<const VecX> x);

  /// The dense output of the last accepted step at time `s` in [step_begin(), step_end()]
  /// (fourth order). After an event the step still covers its whole attempted length (the
  /// event time lies inside it). Precondition: a step has been accepted.
  void Interpolate(double s, Eigen::Ref<VecX> out) const { Interpolate(state_, s, out); }
  /// The same for the last step recorded in `memory`.
  void Interpolate(const AdaptiveOdeState& memory, double s, Eigen::Ref<VecX> out) const;
  [[nodiscard]] double step_begin() const { return state_.t_old; }
  [[nodiscard]] double step_end() const { return state_.t_old + state_.h_old; }
  /// The step size the controller proposes next (0 before the first step).
  [[nodiscard]] double next_step() const { return state_.next_step; }

 private:
  double InitialStep(AdaptiveOdeState& m, const OdeView& system, double t, double t_end,
                     const VecX& x);
  double ErrorNorm(const VecX& x, const VecX& x_new) const;
  // Dense output at fraction θ of the last accepted step in `m` into `out`.
  static void DenseAt(const AdaptiveOdeState& m, double theta, Eigen::Ref<VecX> out);
  // Root of g_i between fractions a < b of the last step with g_i(a) ≤ 0 < g_i(b); returns the
  // fraction on the positive side.
  double LocateRoot(const AdaptiveOdeState& m, const EventFunctions& events, int i, double a,
                    double ga, double b, double gb);

  AdaptiveOdeOptions options_;
  VecX atol_;
  AdaptiveOdeState state_;
  // Work space, rewritten before it is read.
  VecX x_new_, stage_, err_;
  VecX g_old_, g_new_, g_probe_, g_prev_, g_right_;
  VecX dense_;
  Index n_ = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
