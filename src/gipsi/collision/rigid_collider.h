#pragma once
/// @file
/// `RigidCollider`: the capability `Contact` asks of an object it treats as a tool rather than
/// as a deformable body. A collider moves by prescription, is not deformed by contact (the
/// forces on it are reported on its boundary), and may be exactly a capsule (a sphere being a
/// capsule of zero length), which contact then uses instead of its tessellated surface. The
/// built-in `RigidTool` implements it; a plugin's instrument can too, and `Contact` treats it
/// the same way without knowing its type.

#include <optional>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A capsule: the points within `radius` of the segment [start, end] [m]. Plain struct.
struct Capsule {
  Vec3 start = Vec3::Zero();
  Vec3 end = Vec3::Zero();
  double radius = 0;
};

/// Interface, implemented beside SimObject.
class RigidCollider {
 public:
  virtual ~RigidCollider() = default;
  /// The capsule the collider is, at its current placement; std::nullopt for a collider that
  /// is only its boundary surface (a mesh tool).
  [[nodiscard]] virtual std::optional<Capsule> ExactCapsule() const = 0;
  /// Its current (uniform) velocity [m/s].
  [[nodiscard]] virtual Vec3 RigidVelocity() const = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
