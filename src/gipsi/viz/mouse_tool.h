#pragma once
/// @file
/// The mouse as a virtual tool: pick a point on a drawn surface (a ray against the published
/// display triangles) and drag the nearest boundary vertex of that object, through the same
/// boundary-condition path a real tool or collision response uses (a prescribed displacement
/// of a boundary vertex, released when the mouse is let go).

#include <optional>
#include <string>

#include "gipsi/core/sim_object.h"
#include "gipsi/viz/render_buffers.h"

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

/// Drags one boundary vertex of one object. Use from the thread that steps the object, between
/// steps. Not copyable (refers to the object); movable.
class DragTool {
 public:
  /// Grabs the free boundary vertex of `object` nearest to `point` (current positions); returns
  /// false (and grabs nothing) if every boundary vertex is constrained already.
  bool Grab(SimObject& object, const Vec3& point);
  /// Moves the grabbed vertex to `target` (scene coordinates) from the next step on.
  void MoveTo(const Vec3& target);
  /// Lets go: the vertex is free again.
  void Release();
  [[nodiscard]] bool active() const { return object_ != nullptr; }
  [[nodiscard]] Index vertex() const { return vertex_; }
  /// The grabbed vertex's rest position.
  [[nodiscard]] const Vec3& rest() const { return rest_; }

 private:
  SimObject* object_ = nullptr;
  Index vertex_ = -1;
  Vec3 rest_ = Vec3::Zero();
};

}  // namespace gipsi::viz
