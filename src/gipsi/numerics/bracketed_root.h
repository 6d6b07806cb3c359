#pragma once
/// @file
/// `SolveIncreasingRoot`: the root of a scalar increasing function by bracketing and the Illinois
/// (modified regula falsi) iteration — superlinear, and it never leaves the bracket. Used for
/// a cavity's pressure, the p that makes a wall enclose what a blood law fills (FemSolid and
/// MassSpring cavities). Header-only: the function is a template over h and allocates nothing.
///
/// (Illinois: M. Dowell and P. Jarratt, BIT 11:168–174, 1971.)

#include <cmath>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Root of h (increasing) near `guess`. `h(x, out)` sets out = h(x) and returns false if h
/// cannot be evaluated there. `first_step(h(guess))` gives the signed first step of the
/// bracketing search (towards the root); the step doubles until h changes sign (at most 80
/// times). Converged when |h| ≤ `tolerance` or the bracket is 1e-10 of the root (+1) wide.
/// With `slope`, sets it to the secant slope across the first bracket (an estimate of h' for
/// the next call's first step). False if h fails or no root is bracketed; `root` is then
/// unspecified.
template <class H, class FirstStep>
bool SolveIncreasingRoot(H&& h, double guess, FirstStep&& first_step, double tolerance,
                         double& root, double* slope = nullptr) {
  double a = guess, ha = 0;
  if (!h(a, ha)) return false;
  if (std::abs(ha) <= tolerance) {
    root = a;
    return true;
  }
  double step = first_step(ha);
  double b = a, hb = ha;
  bool bracketed = false;
  for (int k = 0; k < 80; ++k) {
    b = a + step;
    if (!h(b, hb)) return false;
    if (std::abs(hb) <= tolerance) {
      root = b;
      if (slope != nullptr) *slope = (hb - ha) / (b - a);
      return true;
    }
    if ((hb > 0) != (ha > 0)) {
      bracketed = true;
      break;
    }
    a = b;
    ha = hb;
    step *= 2;
  }
  if (!bracketed) return false;
  if (slope != nullptr) *slope = (hb - ha) / (b - a);
  int side = 0;
  for (int k = 0; k < 200; ++k) {
    const double c = (a * hb - b * ha) / (hb - ha);
    double hc = 0;
    if (!h(c, hc)) return false;
    if (std::abs(hc) <= tolerance || std::abs(b - a) <= 1e-10 * (std::abs(c) + 1.0)) {
      root = c;
      return true;
    }
    if ((hc > 0) == (hb > 0)) {
      b = c;
      hb = hc;
      if (side == -1) ha *= 0.5;
      side = -1;
    } else {
      a = c;
      ha = hc;
      if (side == 1) hb *= 0.5;
      side = 1;
    }
  }
  root = 0.5 * (a + b);
  return true;
}

}  // namespace gipsi
GIPSI_EXPORT_END
