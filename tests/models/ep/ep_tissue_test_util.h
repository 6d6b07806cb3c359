#pragma once
// Helpers for the monodomain tests: small tissues built in code, and readers of node values.

#include <memory>
#include <vector>

#include "gipsi/geometry/generators.h"
#include "gipsi/models/ep/monodomain.h"
#include "gipsi/models/ep/phenomenological.h"

namespace gipsi::testing {

/// A Nagumo cell (u_t = k u (1 − u)(u − a), V = u) for the exact travelling front.
inline std::shared_ptr<const CellModel> NagumoCell(double k, double a) {
  FitzHughNagumoParams p;
  p.c1 = k;
  p.a = a;
  p.scale = {0.0, 1.0};
  return std::make_shared<FitzHughNagumo>(p, /*with_recovery=*/false);
}

/// Parameters with diffusivities d_l, d_t [mm²/ms] (χ = 1000 /m, Cm = 1 F/m², so σ [S/m] = d).
inline EpTissueParams DiffusionParams(std::shared_ptr<const CellModel> cell, double d_l,
                                      double d_t) {
  EpTissueParams p;
  p.cell = std::move(cell);
  p.surface_to_volume = 1000;
  p.capacitance = 1;
  p.sigma_longitudinal = d_l;
  p.sigma_transverse = d_t;
  p.fibre = Vec3::UnitX();
  return p;
}

/// Steps `object` by `dt` [s] until `end` [s] (or a failed step); returns the last status.
inline StepStatus RunUntil(SimObject& object, double dt, double end) {
  StepStatus status;
  const auto steps = static_cast<long>(std::llround(end / dt));
  for (long s = 0; s < steps && status.ok(); ++s) status = object.Step(dt);
  return status;
}

/// Mean of `values` over the nodes whose coordinates match `x` on the axes with a finite target
/// (within 1e-9 m).
inline double MeanAt(const Mesh& mesh, const VecX& values, double x, double y = NAN,
                     double z = NAN) {
  double sum = 0;
  int count = 0;
  const Vec3 target(x, y, z);
  for (Index i = 0; i < mesh.num_nodes(); ++i) {
    bool match = true;
    for (int a = 0; a < 3; ++a)
      if (std::isfinite(target[a]) && std::abs(mesh.nodes(a, i) - target[a]) > 1e-9) match = false;
    if (!match) continue;
    sum += values[i];
    ++count;
  }
  return count > 0 ? sum / count : NAN;
}

}  // namespace gipsi::testing
