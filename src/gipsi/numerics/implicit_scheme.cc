#include "gipsi/numerics/implicit_scheme.h"

#include "gipsi/base/error.h"

namespace gipsi {

std::string_view ToString(ImplicitSchemeKind kind) {
  switch (kind) {
    case ImplicitSchemeKind::kStatic:
      return "Static";
    case ImplicitSchemeKind::kBackwardEuler:
      return "BackwardEuler";
    case ImplicitSchemeKind::kBdf2:
      return "BDF2";
    case ImplicitSchemeKind::kNewmark:
      return "Newmark";
  }
  return "?";
}

std::optional<ImplicitSchemeKind> ImplicitSchemeNamed(std::string_view name) {
  for (const ImplicitSchemeKind kind : kImplicitSchemeKinds)
    if (name == ToString(kind)) return kind;
  return std::nullopt;
}

ImplicitScheme::ImplicitScheme(ImplicitSchemeKind kind, double newmark_beta, double newmark_gamma)
    : kind_(kind), beta_(newmark_beta), gamma_(newmark_gamma) {
  GIPSI_CHECK(beta_ > 0 && gamma_ > 0);
}

int ImplicitScheme::order() const {
  switch (kind_) {
    case ImplicitSchemeKind::kStatic:
      return 0;
    case ImplicitSchemeKind::kBackwardEuler:
      return 1;
    case ImplicitSchemeKind::kBdf2:
      return 2;
    case ImplicitSchemeKind::kNewmark:
      return gamma_ == 0.5 ? 2 : 1;
  }
  return 0;
}

void ImplicitScheme::Reset(const VecX& x, const VecX& v, const VecX& a) {
  GIPSI_CHECK(x.size() == v.size() && x.size() == a.size());
  x_ = x;
  v_ = v;
  a_ = a;
  dx_prev_ = VecX::Zero(x.size());
  v_prev_ = v;
  a_hat_ = VecX::Zero(x.size());
  v_hat_ = VecX::Zero(x.size());
  dt_prev_ = 0;
}

void ImplicitScheme::SetVelocity(const VecX& v) {
  v_ = v;
  dt_prev_ = 0;
}

void ImplicitScheme::SetPositions(const VecX& x) {
  x_ = x;
  dt_prev_ = 0;
}

void ImplicitScheme::Begin(double dt) {
  GIPSI_CHECK(dt > 0);
  dt_ = dt;
  bdf2_now_ = false;
  switch (kind_) {
    case ImplicitSchemeKind::kStatic:
      c_a_ = c_v_ = 0;
      a_hat_.setZero();
      v_hat_.setZero();
      break;
    case ImplicitSchemeKind::kBdf2:
      if (dt_prev_ == dt) {
        bdf2_now_ = true;
        c_v_ = 1.5 / dt;
        c_a_ = 2.25 / (dt * dt);
        v_hat_ = (-0.5 / dt) * dx_prev_;
        a_hat_ = (1.5 * v_hat_ - 2.0 * v_ + 0.5 * v_prev_) / dt;
        break;
      }
      [[fallthrough]];
    case ImplicitSchemeKind::kBackwardEuler:
      c_v_ = 1.0 / dt;
      c_a_ = 1.0 / (dt * dt);
      v_hat_.setZero();
      a_hat_ = (-1.0 / dt) * v_;
      break;
    case ImplicitSchemeKind::kNewmark:
      c_a_ = 1.0 / (beta_ * dt * dt);
      c_v_ = gamma_ / (beta_ * dt);
      a_hat_ = (-1.0 / (beta_ * dt)) * v_ - (0.5 / beta_ - 1.0) * a_;
      v_hat_ = v_ + dt * (1.0 - gamma_) * a_ + (gamma_ * dt) * a_hat_;
      break;
  }
}

double ImplicitScheme::IncrementForVelocity(Index dof, double v_target) const {
  if (c_v_ == 0) return dt_ * v_target;
  return (v_target - v_hat_[dof]) / c_v_;
}

void ImplicitScheme::Commit(const VecX& d) {
  GIPSI_CHECK(d.size() == x_.size());
  if (kind_ == ImplicitSchemeKind::kStatic) {
    x_ += d;
    dt_prev_ = dt_;
    return;
  }
  v_prev_ = v_;
  // New velocity and acceleration from the affine maps (a uses the old v through â).
  VecX& v_new = v_hat_;  // reuse buffers: v̂ ← c_v d + v̂, â ← c_a d + â
  v_new += c_v_ * d;
  a_hat_ += c_a_ * d;
  // Copied, not swapped: v and a stay at their addresses (the state's velocity is viewed
  // without a copy from Python); two vector copies are negligible against a step.
  v_ = v_new;
  a_ = a_hat_;
  x_ += d;
  dx_prev_ = d;
  dt_prev_ = dt_;
}

void PredictIncrement(const ImplicitScheme& scheme, StepPredictor predictor, double h, VecX& d) {
  if (predictor == StepPredictor::kNone) {
    d.setZero();  // keeps d's size (a static scheme has no velocities)
    return;
  }
  const VecX& v = scheme.v();
  const VecX& a = scheme.a();
  d.resize(v.size());
  switch (predictor) {
    case StepPredictor::kNone:
      return;
    case StepPredictor::kConstantVelocity:
      d = h * v;
      return;
    case StepPredictor::kConstantAcceleration:
      for (Index i = 0; i < d.size(); ++i) d[i] = scheme.IncrementForVelocity(i, v[i] + h * a[i]);
      return;
  }
}

}  // namespace gipsi
