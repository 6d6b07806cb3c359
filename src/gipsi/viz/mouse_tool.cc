#include "gipsi/viz/mouse_tool.h"

#include <limits>

namespace gipsi::viz {

std::optional<SurfaceHit> PickSurface(const FrameBuffers& frame, const Vec3& origin,
                                      const Vec3& direction, const std::vector<bool>& hidden) {
  const Vec3 d = direction.normalized();
  std::optional<SurfaceHit> best;
  for (std::size_t s = 0; s < frame.surfaces.size(); ++s) {
    if (s < hidden.size() && hidden[s]) continue;
    const SurfaceBuffers& surface = frame.surfaces[s];
    auto vertex = [&](std::uint32_t i) {
      return Vec3(surface.positions[3 * i], surface.positions[3 * i + 1],
                  surface.positions[3 * i + 2]);
    };
    for (std::size_t t = 0; t < surface.num_triangles(); ++t) {
      const Vec3 a = vertex(surface.indices[3 * t]), b = vertex(surface.indices[3 * t + 1]),
                 c = vertex(surface.indices[3 * t + 2]);
      const Vec3 e1 = b - a, e2 = c - a, p = d.cross(e2);
      const double det = e1.dot(p);
      if (std::abs(det) < 1e-300) continue;  // parallel to the triangle
      const Vec3 q = origin - a;
      const double u = q.dot(p) / det;
      if (u < 0 || u > 1) continue;
      const Vec3 r = q.cross(e1);
      const double v = d.dot(r) / det;
      if (v < 0 || u + v > 1) continue;
      const double distance = e2.dot(r) / det;
      if (distance <= 0 || (best && distance >= best->distance)) continue;
      best = SurfaceHit{s, t, distance, origin + distance * d};
    }
  }
  return best;
}

bool DragTool::Grab(SimObject& object, const Vec3& point) {
  Release();
  const BoundarySurface& boundary = object.boundary();
  const Points& x = object.domain_positions();
  const BoundaryConditions& bcs = object.boundary_conditions();
  double nearest = std::numeric_limits<double>::infinity();
  for (Index v = 0; v < boundary.num_vertices(); ++v) {
    if (bcs.kind(v, 0) != ConstraintKind::kFree || bcs.kind(v, 1) != ConstraintKind::kFree ||
        bcs.kind(v, 2) != ConstraintKind::kFree)
      continue;  // held by the scene: not ours to move or to release
    const double dist = (x.col(boundary.vertex_to_node[std::size_t(v)]) - point).squaredNorm();
    if (dist < nearest) {
      nearest = dist;
      vertex_ = v;
    }
  }
  if (vertex_ < 0) return false;
  object_ = &object;
  rest_ = object.domain().nodes.col(boundary.vertex_to_node[std::size_t(vertex_)]);
  MoveTo(x.col(boundary.vertex_to_node[std::size_t(vertex_)]));
  return true;
}

void DragTool::MoveTo(const Vec3& target) {
  if (!object_) return;
  object_->boundary_conditions().PrescribeDisplacement(vertex_, target - rest_);
}

void DragTool::Release() {
  if (object_) object_->boundary_conditions().Release(vertex_);
  object_ = nullptr;
  vertex_ = -1;
}

}  // namespace gipsi::viz
