#pragma once
/// @file
/// Normalised activation e(t) ∈ [0, 1] of a time-varying-elastance heart chamber,
/// E(t) = E_min + (E_max − E_min) e(t), periodic with the heart period.
///
/// Shapes:
///  - "double_hill" (Stergiopulos, Meister & Westerhof, Am. J. Physiol. 270:H2050, 1996):
///      e(t) = k · g1/(1 + g1) · 1/(1 + g2),  g1 = (τ/τ1)^m1,  g2 = (τ/τ2)^m2,
///    τ = (t − onset) mod T, k normalising the maximum to 1. Their left-ventricular values are
///    τ1 = 0.269 T, τ2 = 0.452 T, m1 = 1.32, m2 = 27.4 (fitted to the normalised human
///    elastance curve of Senzaki et al., Circulation 94:2497, 1996).
///  - "cosine": a raised cosine rising over `contraction` seconds and falling over `relaxation`
///    seconds, 0 for the rest of the cycle (the shape used e.g. by Regazzoni et al., J. Comput.
///    Phys. 457:111083, 2022):
///      e = ½(1 − cos(π τ/Tc)) for τ < Tc;  ½(1 + cos(π (τ − Tc)/Tr)) for Tc ≤ τ < Tc + Tr.

#include <string>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Parameters of an activation curve. Plain struct; copyable. Call Normalise() after setting
/// the double-Hill parameters (the factory does).
struct Activation {
  enum class Shape { kDoubleHill, kCosine };
  Shape shape = Shape::kDoubleHill;
  double period = 0.8;  ///< heart period T [s], > 0
  double onset = 0;     ///< start of contraction within the cycle [s]
  // Double Hill (defaults: Stergiopulos et al. 1996, left ventricle, T = 0.8 s).
  double tau1 = 0.269 * 0.8;  ///< [s]
  double tau2 = 0.452 * 0.8;  ///< [s]
  double m1 = 1.32;
  double m2 = 27.4;
  // Cosine.
  double contraction = 0.3;  ///< Tc [s]
  double relaxation = 0.15;  ///< Tr [s]; Tc + Tr ≤ T
  double scale = 1;          ///< k of the double Hill (set by Normalise)

  /// e(t) in [0, 1].
  [[nodiscard]] double Evaluate(double t) const;
  /// Sets `scale` so that the double Hill's maximum over a cycle is 1 (a no-op for cosine).
  void Normalise();
};

}  // namespace gipsi
GIPSI_EXPORT_END
