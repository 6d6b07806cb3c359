#include "gipsi/models/circulation/activation.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace gipsi {
namespace {

double DoubleHill(const Activation& a, double tau) {
  const double g1 = std::pow(tau / a.tau1, a.m1);
  const double g2 = std::pow(tau / a.tau2, a.m2);
  return g1 / (1 + g1) / (1 + g2);
}

}  // namespace

double Activation::Evaluate(double t) const {
  double tau = std::fmod(t - onset, period);
  if (tau < 0) tau += period;
  if (shape == Shape::kDoubleHill) return scale * DoubleHill(*this, tau);
  if (tau < contraction) return 0.5 * (1 - std::cos(std::numbers::pi * tau / contraction));
  if (tau < contraction + relaxation)
    return 0.5 * (1 + std::cos(std::numbers::pi * (tau - contraction) / relaxation));
  return 0;
}

void Activation::Normalise() {
  if (shape != Shape::kDoubleHill) return;
  // The double Hill is unimodal on [0, T]: bracket the maximum on a grid, then refine it by
  // golden-section search to relative 1e-15.
  constexpr int kSamples = 4000;
  int best = 0;
  double best_value = 0;
  for (int i = 1; i <= kSamples; ++i) {
    const double v = DoubleHill(*this, period * i / kSamples);
    if (v > best_value) {
      best_value = v;
      best = i;
    }
  }
  double lo = period * std::max(best - 1, 0) / kSamples;
  double hi = period * std::min(best + 1, kSamples) / kSamples;
  const double r = (std::sqrt(5.0) - 1) / 2;
  for (int it = 0; it < 200 && hi - lo > 1e-15 * period; ++it) {
    const double a = hi - r * (hi - lo), b = lo + r * (hi - lo);
    if (DoubleHill(*this, a) < DoubleHill(*this, b))
      lo = a;
    else
      hi = b;
  }
  const double peak = DoubleHill(*this, 0.5 * (lo + hi));
  scale = peak > 0 ? 1 / peak : 1;
}

}  // namespace gipsi
