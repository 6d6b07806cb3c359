#pragma once
/// @file
/// The mouse as a virtual tool: pick a point on a drawn surface (a ray against the published
/// display triangles) and pull the object there through a bounded spring attached to the
/// nearest free node of its *domain* boundary (not a vertex of a finer display surface). The
/// spring's force goes into the object's `external_force` node field between macro steps, so
/// the object integrates it like any other load, at its own rate and with its own integrator.
///
/// Why a bounded spring and not a prescribed displacement: a prescribed displacement jumps a
/// node to wherever the mouse is, however far, in one step; an explicit integrator (a
/// mass-spring liver) then diverges, and an implicit one (a FEM muscle) may fail to converge.
/// The spring is scaled to the object at the grabbed node (docs/visualization.md#the-mouse-pull):
///   - its stiffness is a quarter of the smallest eigenvalue of K_c, the 3 × 3 stiffness the
///     tissue offers a point load there (the object's haptic local model, condensed at the
///     node: gipsi/core/local_model.h). The force is computed from the node's
///     position at the start of each macro step and held through it; the node answers a held
///     force F with at most 2 F / λ_min(K_c) (a step response overshoots by at most 2), so one
///     macro step changes the spring's force by at most half of its change before: the lagged
///     coupling converges instead of ringing up;
///   - a force held over a macro step of length T lags the node by T/2 on average, which acts as
///     a negative damping of k T/2 on slow motions (the whole object swinging on the tool): the
///     tool damps the node's velocity (its mean over the last macro step) with c = 1.5 k T, more
///     than cancelling it, but at most m / (2 T) with m the node's mass, so that the held
///     damping force itself stays stable;
///   - its force is capped at F_max = λ_max(K_c) · δ with δ a fifth of the mean rest length of
///     the domain edges at the node, so whatever the drag, the tool can move the node by about
///     a fifth of an element from where the tissue would otherwise be: no spring is
///     over-stretched, no element inverted.
/// A drag that has not moved the mouse from the grab point applies no force (a no-op).

#include <memory>
#include <optional>
#include <string>

#include "gipsi/base/export.h"
#include "gipsi/core/local_model.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/viz/render_buffers.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// Where a ray first meets a surface of a frame. Plain struct.
struct SurfaceHit {
  std::size_t surface = 0;  ///< index into FrameBuffers::surfaces
  std::size_t triangle = 0;
  double distance = 0;  ///< along the ray (ray direction normalised)
  Vec3 point;           ///< scene coordinates
};

/// The first intersection of the ray origin + s·direction (s > 0) with the triangles of the
/// visible surfaces of `frame` (Möller–Trumbore), or std::nullopt. `hidden[i]` hides surface i.
std::optional<SurfaceHit> PickSurface(const FrameBuffers& frame, const Vec3& origin,
                                      const Vec3& direction, const std::vector<bool>& hidden = {});

/// The bounded spring of a pull at one node. Plain struct.
struct PullSpring {
  double stiffness = 0;  ///< k [N/m]
  double damping = 0;    ///< c [N·s/m], on the node's velocity
  double max_force = 0;  ///< F_max [N]
};

/// The spring the mouse pull attaches with at the node of boundary vertex `vertex`, scaled to
/// the object there (see the file comment): `builder` is the object's haptic local-model
/// builder, `period` the macro step [s]. std::nullopt if the vertex is constrained or the
/// tissue offers no stiffness there (the local model is singular). Simulation thread only.
std::optional<PullSpring> ScalePullSpring(LocalModelBuilder& builder, Index vertex, double period);

/// The force on a node at `x` moving at `v` pulled towards `target` by `spring`:
/// k (target − x) − c v, scaled down to F_max when longer [N].
Vec3 PullForce(const PullSpring& spring, const Vec3& target, const Vec3& x,
               const Vec3& v = Vec3::Zero());

/// Pulls one node of one object with a bounded spring. Use from the thread that steps the
/// object, between macro steps. Not copyable (holds the builder and refers to the object);
/// movable.
class PullTool {
 public:
  /// Grabs the free boundary vertex of `builder.object()` nearest to `point` (the picked point,
  /// current positions; vertices the scene holds are never taken) and scales the spring there
  /// for macro steps of `period` [s]. Returns "" on success, else why nothing was grabbed.
  std::string Grab(std::unique_ptr<LocalModelBuilder> builder, const Vec3& point, double period);
  /// The mouse's point in the scene: the grabbed node is pulled towards it plus the node's
  /// offset from the picked point at the grab. No force until the target differs from the
  /// picked point.
  void MoveTo(const Vec3& target);
  /// Writes the spring's force for the coming macro step into the object's `external_force`
  /// (replacing what it wrote before; other loads there are kept). Call before every macro step
  /// while active. Allocates nothing.
  void Apply();
  /// Lets go: takes its force back out of `external_force`.
  void Release();
  [[nodiscard]] bool active() const { return builder_ != nullptr; }
  /// The object pulled. Precondition: active().
  [[nodiscard]] SimObject& object() const { return builder_->object(); }
  [[nodiscard]] Index vertex() const { return vertex_; }
  [[nodiscard]] const PullSpring& spring() const { return spring_; }
  /// The force written by the last Apply [N].
  [[nodiscard]] const Vec3& force() const { return force_; }

 private:
  void Write(const Vec3& force);

  std::unique_ptr<LocalModelBuilder> builder_;
  Index vertex_ = -1;
  Index node_ = -1;
  PullSpring spring_;
  Vec3 picked_ = Vec3::Zero(), offset_ = Vec3::Zero(), target_ = Vec3::Zero();
  Vec3 last_x_ = Vec3::Zero();  // the node's position at the last Apply
  double last_time_ = 0;        // the object's time then
  bool moved_ = false;
  Vec3 force_ = Vec3::Zero();
  FieldId external_force_{};
  Eigen::MatrixXd loads_;  // 3 by nodes: the object's external_force
};

}  // namespace gipsi::viz
GIPSI_EXPORT_END
