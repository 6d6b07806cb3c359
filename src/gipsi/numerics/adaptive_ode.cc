#include "gipsi/numerics/adaptive_ode.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "gipsi/base/error.h"

namespace gipsi {
namespace {

// Dormand–Prince 5(4) tableau (Dormand & Prince 1980). Stage k7 = f(t + h, x_new) is the
// first stage of the next step (FSAL).
constexpr double kC2 = 1.0 / 5, kC3 = 3.0 / 10, kC4 = 4.0 / 5, kC5 = 8.0 / 9;
constexpr double kA21 = 1.0 / 5;
constexpr double kA31 = 3.0 / 40, kA32 = 9.0 / 40;
constexpr double kA41 = 44.0 / 45, kA42 = -56.0 / 15, kA43 = 32.0 / 9;
constexpr double kA51 = 19372.0 / 6561, kA52 = -25360.0 / 2187, kA53 = 64448.0 / 6561,
                 kA54 = -212.0 / 729;
constexpr double kA61 = 9017.0 / 3168, kA62 = -355.0 / 33, kA63 = 46732.0 / 5247, kA64 = 49.0 / 176,
                 kA65 = -5103.0 / 18656;
// Fifth-order weights (b2 = b7 = 0).
constexpr double kB1 = 35.0 / 384, kB3 = 500.0 / 1113, kB4 = 125.0 / 192, kB5 = -2187.0 / 6784,
                 kB6 = 11.0 / 84;
// Error weights: fifth-order minus embedded fourth-order weights (5179/57600, 0, 7571/16695,
// 393/640, −92097/339200, 187/2100, 1/40).
constexpr double kE1 = 71.0 / 57600, kE3 = -71.0 / 16695, kE4 = 71.0 / 1920,
                 kE5 = -17253.0 / 339200, kE6 = 22.0 / 525, kE7 = -1.0 / 40;
// Continuous extension: b_i(θ) = Σ_j kP[i][j] θ^(j+1), x(t + θh) = x + h Σ_i b_i(θ) k_i;
// b_i(1) are the fifth-order weights and Σ_i b_i(θ) = θ (checked by the tests).
constexpr double kP[7][4] = {
    {1.0, -8048581381.0 / 2820520608, 8663915743.0 / 2820520608, -12715105075.0 / 11282082432},
    {0, 0, 0, 0},
    {0, 131558114200.0 / 32700410799, -68118460800.0 / 10900136933, 87487479700.0 / 32700410799},
    {0, -1754552775.0 / 470086768, 14199869525.0 / 1410260304, -10690763975.0 / 1880347072},
    {0, 127303824393.0 / 49829197408, -318862633887.0 / 49829197408, 701980252875.0 / 199316789632},
    {0, -282668133.0 / 205662961, 2019193451.0 / 616988883, -1453857185.0 / 822651844},
    {0, 40617522.0 / 29380423, -110615467.0 / 29380423, 69997945.0 / 29380423}};

bool AllFinite(const VecX& v) { return v.allFinite(); }

}  // namespace

void AdaptiveOde::Prepare(Index n, int num_events, const AdaptiveOdeOptions& options) {
  GIPSI_CHECK(n >= 1, "AdaptiveOde needs a state, got size {}", n);
  GIPSI_CHECK(num_events >= 0);
  GIPSI_CHECK(options.relative_tolerance > 0 && options.absolute_tolerance > 0 &&
                  options.event_tolerance > 0 && options.max_step > 0 &&
                  options.event_samples >= 1 && options.max_steps >= 1 && options.initial_step >= 0,
              "AdaptiveOde: tolerances, max_step, event_samples and max_steps must be positive");
  GIPSI_CHECK(options.absolute_tolerances.size() == 0 || options.absolute_tolerances.size() == n,
              "absolute_tolerances has size {}, the state {}", options.absolute_tolerances.size(),
              n);
  options_ = options;
  n_ = n;
  atol_ = options.absolute_tolerances.size() == n ? options.absolute_tolerances
                                                  : VecX::Constant(n, options.absolute_tolerance);
  GIPSI_CHECK((atol_.array() > 0).all(), "absolute tolerances must be positive");
  x_new_.setZero(n);
  stage_.setZero(n);
  err_.setZero(n);
  dense_.setZero(n);
  g_old_.setZero(num_events);
  g_new_.setZero(num_events);
  g_probe_.setZero(num_events);
  g_prev_.setZero(num_events);
  g_right_.setZero(num_events);
  state_ = NewState();
}

AdaptiveOdeState AdaptiveOde::NewState() const {
  AdaptiveOdeState state;
  state.next_step = options_.initial_step > 0 ? options_.initial_step : 0;
  state.x_old.setZero(n_);
  for (VecX& k : state.k) k.setZero(n_);
  return state;
}

double AdaptiveOde::ErrorNorm(const VecX& x, const VecX& x_new) const {
  double sum = 0;
  for (Index i = 0; i < n_; ++i) {
    const double scale =
        atol_[i] + options_.relative_tolerance * std::max(std::abs(x[i]), std::abs(x_new[i]));
    const double e = err_[i] / scale;
    sum += e * e;
  }
  return std::sqrt(sum / static_cast<double>(n_));
}

double AdaptiveOde::InitialStep(AdaptiveOdeState& m, const OdeView& system, double t, double t_end,
                                const VecX& x) {
  // Hairer, Nørsett & Wanner, Solving ODEs I, §II.4: balance the first Euler step's size
  // against the scale of x and of the change of f.
  const VecX& f0 = m.k[0];
  auto rms_scaled = [&](auto&& v) {
    double sum = 0;
    for (Index i = 0; i < n_; ++i) {
      const double e = v[i] / (atol_[i] + options_.relative_tolerance * std::abs(x[i]));
      sum += e * e;
    }
    return std::sqrt(sum / static_cast<double>(n_));
  };
  const double d0 = rms_scaled(x);
  const double d1 = rms_scaled(f0);
  double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  h0 = std::min({h0, t_end - t, options_.max_step});
  stage_.noalias() = x + h0 * f0;
  system.CalcDerivative(t + h0, stage_, m.k[1]);
  err_.noalias() = m.k[1] - f0;
  const double d2 = rms_scaled(err_) / h0;
  const double dm = std::max(d1, d2);
  const double h1 = dm <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dm, 1.0 / 5);
  double h = std::min({100 * h0, h1, options_.max_step});
  return std::isfinite(h) && h > 0 ? h : h0;
}

void AdaptiveOde::DenseAt(const AdaptiveOdeState& m, double theta, Eigen::Ref<VecX> out) {
  double w[7];
  for (int i = 0; i < 7; ++i)
    w[i] = theta * (kP[i][0] + theta * (kP[i][1] + theta * (kP[i][2] + theta * kP[i][3])));
  out = m.x_old;
  for (std::size_t i = 0; i < 7; ++i)
    if (w[i] != 0) out.noalias() += (m.h_old * w[i]) * m.k[i];
}

void AdaptiveOde::Interpolate(const AdaptiveOdeState& memory, double s,
                              Eigen::Ref<VecX> out) const {
  GIPSI_CHECK(memory.have_step, "Interpolate before any accepted step");
  GIPSI_CHECK(out.size() == n_ && memory.x_old.size() == n_);
  const double theta = memory.h_old > 0 ? (s - memory.t_old) / memory.h_old : 0.0;
  DenseAt(memory, std::clamp(theta, 0.0, 1.0), out);
}

int AdaptiveOde::FirstPositive(const EventFunctions& events, double t, Eigen::Ref<const VecX> x) {
  GIPSI_CHECK(events.num_events() <= g_probe_.size(), "more event functions than prepared");
  auto g = g_probe_.head(events.num_events());
  events.Calc(t, x, g);
  for (int i = 0; i < events.num_events(); ++i)
    if (g[i] > 0) return i;
  return -1;
}

double AdaptiveOde::LocateRoot(const AdaptiveOdeState& m, const EventFunctions& events, int i,
                               double a, double ga, double b, double gb) {
  // Illinois variant of regula falsi, with a bisection every third iteration so that the
  // bracket [a, b] (g(a) ≤ 0 < g(b)) shrinks below the tolerance whatever the function's shape.
  const double width_tolerance = options_.event_tolerance / m.h_old;
  auto g = g_probe_.head(events.num_events());
  int side = 0;
  for (int iteration = 0; iteration < 200 && b - a > width_tolerance; ++iteration) {
    double c = (iteration % 3 == 2) ? 0.5 * (a + b) : b - gb * (b - a) / (gb - ga);
    if (!(c > a && c < b)) c = 0.5 * (a + b);
    DenseAt(m, c, dense_);
    events.Calc(m.t_old + c * m.h_old, dense_, g);
    const double gc = g[i];
    if (gc > 0) {
      b = c;
      gb = gc;
      if (side == 1) ga *= 0.5;
      side = 1;
    } else {
      a = c;
      ga = gc;
      if (side == -1) gb *= 0.5;
      side = -1;
    }
  }
  return b;
}

AdaptiveOdeResult AdaptiveOde::Integrate(AdaptiveOdeState& mem, const OdeView& system, double& t,
                                         double t_end, Eigen::Ref<VecX> x,
                                         const EventFunctions* events) {
  GIPSI_CHECK(system.size() == n_ && x.size() == n_ && mem.x_old.size() == n_,
              "AdaptiveOde prepared for {}, got {} (a state of size {})", n_, system.size(),
              mem.x_old.size());
  GIPSI_CHECK(events == nullptr || events->num_events() <= g_old_.size(),
              "more event functions than prepared");
  using Outcome = AdaptiveOdeResult::Outcome;
  AdaptiveOdeResult result;
  if (!(t_end > t)) return result;
  const int m = events ? events->num_events() : 0;

  system.CalcDerivative(t, x, mem.k[0]);
  ++result.evaluations;
  if (!AllFinite(mem.k[0])) {
    result.outcome = Outcome::kNonFinite;
    return result;
  }
  if (m > 0) events->Calc(t, x, g_old_.head(m));
  if (!(mem.next_step > 0)) {
    x_new_ = x;  // InitialStep reads a plain vector
    mem.next_step = InitialStep(mem, system, t, t_end, x_new_);
    ++result.evaluations;
  }
  bool rejected_last = false;
  bool fsal_pending =
      false;  // mem.k[6] holds f at the new x; it becomes mem.k[0] at the next attempt
  for (std::int64_t attempt = 0;; ++attempt) {
    if (fsal_pending) {
      // Deferred so that mem.k keeps the last accepted step's stages for Interpolate.
      std::swap(mem.k[0], mem.k[6]);
      fsal_pending = false;
    }
    if (attempt >= options_.max_steps) {
      result.outcome = Outcome::kTooManySteps;
      return result;
    }
    const double remaining = t_end - t;
    double h = std::min(mem.next_step, options_.max_step);
    const bool last = h >= remaining * (1 - 1e-12);
    if (last) h = remaining;
    if (!last && h < options_.min_step_factor * std::max(std::abs(t), 1.0)) {
      result.outcome = Outcome::kStepTooSmall;
      return result;
    }
    // Stages.
    stage_.noalias() = x + (h * kA21) * mem.k[0];
    system.CalcDerivative(t + kC2 * h, stage_, mem.k[1]);
    stage_.noalias() = x + h * (kA31 * mem.k[0] + kA32 * mem.k[1]);
    system.CalcDerivative(t + kC3 * h, stage_, mem.k[2]);
    stage_.noalias() = x + h * (kA41 * mem.k[0] + kA42 * mem.k[1] + kA43 * mem.k[2]);
    system.CalcDerivative(t + kC4 * h, stage_, mem.k[3]);
    stage_.noalias() =
        x + h * (kA51 * mem.k[0] + kA52 * mem.k[1] + kA53 * mem.k[2] + kA54 * mem.k[3]);
    system.CalcDerivative(t + kC5 * h, stage_, mem.k[4]);
    stage_.noalias() = x + h * (kA61 * mem.k[0] + kA62 * mem.k[1] + kA63 * mem.k[2] +
                                kA64 * mem.k[3] + kA65 * mem.k[4]);
    system.CalcDerivative(t + h, stage_, mem.k[5]);
    x_new_.noalias() = x + h * (kB1 * mem.k[0] + kB3 * mem.k[2] + kB4 * mem.k[3] + kB5 * mem.k[4] +
                                kB6 * mem.k[5]);
    const double t_new = last ? t_end : t + h;
    system.CalcDerivative(t_new, x_new_, mem.k[6]);
    result.evaluations += 6;
    err_.noalias() = h * (kE1 * mem.k[0] + kE3 * mem.k[2] + kE4 * mem.k[3] + kE5 * mem.k[4] +
                          kE6 * mem.k[5] + kE7 * mem.k[6]);
    const double error = ErrorNorm(x, x_new_);
    if (!std::isfinite(error) || !AllFinite(mem.k[6])) {
      // A too-large step on a stiff problem may overflow: retry much smaller.
      ++result.rejected;
      mem.next_step = 0.1 * h;
      rejected_last = true;
      if (mem.next_step < options_.min_step_factor * std::max(std::abs(t), 1.0)) {
        result.outcome = Outcome::kNonFinite;
        return result;
      }
      continue;
    }
    if (error > 1) {
      ++result.rejected;
      mem.next_step = h * std::max(0.2, 0.9 * std::pow(error, -0.2));
      rejected_last = true;
      continue;
    }
    // Accepted.
    ++result.accepted;
    mem.x_old = x;
    mem.t_old = t;
    mem.h_old = h;
    mem.have_step = true;
    double factor = error == 0 ? 5.0 : std::min(5.0, std::max(0.2, 0.9 * std::pow(error, -0.2)));
    if (rejected_last) factor = std::min(factor, 1.0);
    const double proposal = h * factor;
    mem.next_step = last ? std::max(mem.next_step, proposal) : proposal;
    rejected_last = false;

    if (m > 0) {
      events->Calc(t_new, x_new_, g_new_.head(m));
      // Scan sub-intervals [θ_{k−1}, θ_k] for the first upward crossing; g_probe_ holds g at
      // θ_k (the last one is g_new_), g_prev_ at θ_{k−1}.
      auto g_prev = g_prev_.head(m);
      g_prev = g_old_.head(m);
      const int samples = options_.event_samples;
      double theta_prev = 0;
      for (int k = 1; k <= samples; ++k) {
        const double theta = static_cast<double>(k) / samples;
        auto g_here = g_probe_.head(m);
        if (k == samples) {
          g_here = g_new_.head(m);
        } else {
          DenseAt(mem, theta, dense_);
          events->Calc(t + theta * h, dense_, g_here);
        }
        int first = -1;
        double first_theta = 2;
        bool crossed = false;
        for (int i = 0; i < m; ++i) crossed = crossed || (g_prev[i] <= 0 && g_here[i] > 0);
        if (crossed) {
          // Copy the bracket values before LocateRoot reuses g_probe_.
          g_right_.head(m) = g_here;
          for (int i = 0; i < m; ++i) {
            if (!(g_prev[i] <= 0 && g_right_[i] > 0)) continue;
            const double root =
                LocateRoot(mem, *events, i, theta_prev, g_prev[i], theta, g_right_[i]);
            if (root < first_theta) {
              first_theta = root;
              first = i;
            }
          }
          DenseAt(mem, first_theta, x);
          t = t + first_theta * h;
          result.outcome = Outcome::kEvent;
          result.event = first;
          return result;
        }
        g_prev = g_here;
        theta_prev = theta;
      }
      g_old_.head(m) = g_new_.head(m);
    }
    x = x_new_;
    fsal_pending = true;
    t = t_new;
    if (last) {
      result.outcome = Outcome::kReachedEnd;
      return result;
    }
  }
}

}  // namespace gipsi
