#pragma once
/// @file
/// `RigidTool`: a rigid surgical tool (probe, grasper jaw, instrument shaft) whose motion is
/// prescribed, for collision with deformable objects. Its shape is a sphere, a capsule (a
/// segment swept by a radius; contacts use the exact primitive) or a triangle mesh. It
/// translates along a scripted path (piecewise-linear keyframes) or with a constant velocity.
/// Contact forces reach it, like any object, as coupling forces on its boundary vertices; its
/// field "contact_force" is their sum (the force the tissue exerts on the tool).
///
/// Scene: {"type": "RigidTool", "shape": "sphere" | "capsule" | "mesh", "radius": r,
///         "length": L (capsule), "domain": mesh name (shape "mesh"), "segments": 16,
///         "position": [x, y, z], "path": [[t, dx, dy, dz], ...] | "velocity": [vx, vy, vz],
///         "dt": ...}

#include <memory>
#include <optional>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/collision/rigid_collider.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Shape and motion of a tool. Plain struct with defaults.
struct RigidToolSpec {
  enum class Shape { kSphere, kCapsule, kMesh };
  Shape shape = Shape::kSphere;
  double radius = 0.005;  ///< m (sphere, capsule)
  double length = 0;      ///< m (capsule: the axis runs from the reference point along +z)
  int segments = 16;      ///< divisions around the axis of the generated surface
  /// Where the reference point (sphere centre, capsule axis start; mesh origin) is at rest [m].
  Vec3 position = Vec3::Zero();
  /// Keyframes (time [s], offset [m] from `position`), times strictly increasing; the offset is
  /// interpolated linearly and held outside the keyframes. Empty: use `velocity`.
  std::vector<std::pair<double, Vec3>> path;
  Vec3 velocity = Vec3::Zero();  ///< m/s, when there is no path
};

/// What a rigid tool carries from one step to the next (a state value type; the rest is the
/// scene's motion law). Copyable.
struct RigidToolState {
  Vec3 offset = Vec3::Zero();    ///< translation from the rest placement [m]
  Vec3 velocity = Vec3::Zero();  ///< [m/s]

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("offset", s.offset);
    v("velocity", s.velocity);
  }
};

/// Not copyable or movable (a SimObject).
class RigidTool final : public SimObject, public RigidCollider {
 public:
  /// `mesh` is the tool's triangle surface (in the tool frame) for Shape::kMesh, ignored (and
  /// may be null) otherwise. Throws InputError for a bad spec or mesh.
  RigidTool(std::string name, const RigidToolSpec& spec, std::shared_ptr<const Mesh> mesh);

  [[nodiscard]] std::string_view type_name() const override { return "RigidTool"; }
  [[nodiscard]] const Points& domain_positions() const override { return positions_; }
  [[nodiscard]] const RigidToolSpec& spec() const { return spec_; }
  /// True for sphere and capsule tools (contacts use the exact primitive).
  [[nodiscard]] bool is_primitive() const { return spec_.shape != RigidToolSpec::Shape::kMesh; }
  /// Current axis segment of a primitive tool (equal points for a sphere) [m].
  [[nodiscard]] Vec3 axis_start() const { return spec_.position + state_.offset; }
  [[nodiscard]] Vec3 axis_end() const {
    return spec_.position + state_.offset + Vec3(0, 0, spec_.length);
  }
  /// RigidCollider: the capsule of a sphere or capsule tool (none for a mesh tool), and its
  /// velocity.
  [[nodiscard]] std::optional<Capsule> ExactCapsule() const override {
    if (!is_primitive()) return std::nullopt;
    return Capsule{axis_start(), axis_end(), spec_.radius};
  }
  [[nodiscard]] Vec3 RigidVelocity() const override { return state_.velocity; }
  /// Current translation from the rest placement [m] and velocity [m/s].
  [[nodiscard]] const Vec3& offset() const { return state_.offset; }
  [[nodiscard]] const Vec3& velocity() const { return state_.velocity; }
  /// Sum of the boundary forces on the tool [N]: what contact exerts on it this macro step.
  [[nodiscard]] Vec3 ContactForce() const;
  /// The prescribed offset at time t.
  [[nodiscard]] Vec3 OffsetAt(double t) const;

 protected:
  StepStatus DoStep(double t, double dt) override;
  /// After a checkpoint or snapshot restore: places the nodes.
  void StateRestored() override { Place(); }
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

 private:
  void Place();
  RigidToolSpec spec_;
  RigidToolState state_;  // checkpoints and step retries (BindState)
  Points positions_;
  FieldId f_position_, f_velocity_, f_displacement_;
  FieldId f_bposition_, f_bvelocity_, f_bdisplacement_, f_force_, f_offset_;
};

/// Registers "RigidTool".
void RegisterRigidTool(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
