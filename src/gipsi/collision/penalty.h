#pragma once
/// @file
/// Penalty contact response: the force one body receives at a contact closer than the contact
/// thickness (the other body receives the opposite force, so momentum is conserved exactly).
///
///   f_n = max(0, k (d − g) − c v_n),   f_t = −μ f_n v_t / sqrt(|v_t|² + ε²),   f = f_n n + f_t
///
/// with d the contact thickness [m], g the signed gap [m] (negative once penetrated), n the unit
/// normal pointing toward the body that receives f, v = v_this − v_other the relative velocity
/// [m/s], v_n = v · n, v_t = v − v_n n; k the penalty stiffness [N/m per contact], c the damping
/// [N·s/m per contact], μ the Coulomb friction coefficient and ε the slip velocity [m/s] below
/// which friction is regularised (viscous), which keeps the explicit exchange smooth.
/// The damping term never pulls (f_n is clamped at zero).

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Contact parameters. Plain struct with defaults.
struct ContactMaterial {
  double thickness = 1e-3;      ///< m: contacts act closer than this
  double stiffness = 1e3;       ///< N/m per contact
  double damping = 0;           ///< N·s/m per contact, on the normal approach velocity
  double friction = 0;          ///< Coulomb coefficient μ
  double slip_velocity = 1e-3;  ///< m/s, friction regularisation ε
};

/// The force on the body that `normal` points to (see the file comment). Zero when gap >=
/// thickness.
inline Vec3 PenaltyForce(const ContactMaterial& m, double gap, const Vec3& normal,
                         const Vec3& relative_velocity) {
  if (!(gap < m.thickness)) return Vec3::Zero();
  const double vn = relative_velocity.dot(normal);
  const double fn = m.stiffness * (m.thickness - gap) - m.damping * vn;
  if (!(fn > 0)) return Vec3::Zero();
  Vec3 f = fn * normal;
  if (m.friction > 0) {
    const Vec3 vt = relative_velocity - vn * normal;
    f -= (m.friction * fn / std::sqrt(vt.squaredNorm() + m.slip_velocity * m.slip_velocity)) * vt;
  }
  return f;
}

}  // namespace gipsi
GIPSI_EXPORT_END
