#include "gipsi/viz/mouse_tool.h"

#include <algorithm>
#include <limits>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

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

namespace {

/// Mean rest length of the domain edges at `node` (tets, else triangles) [m]; 0 if none.
double MeanEdgeLength(const Mesh& mesh, Index node) {
  double sum = 0;
  int count = 0;
  auto visit = [&](const auto& cells) {
    for (Index e = 0; e < cells.cols(); ++e)
      for (Index a = 0; a < cells.rows(); ++a)
        if (cells(a, e) == node)
          for (Index b = 0; b < cells.rows(); ++b)
            if (b != a) {
              sum += (mesh.nodes.col(cells(b, e)) - mesh.nodes.col(node)).norm();
              ++count;
            }
  };
  if (mesh.num_tets() > 0)
    visit(mesh.tets);
  else
    visit(mesh.triangles);
  return count > 0 ? sum / count : 0.0;
}

}  // namespace

std::optional<PullSpring> ScalePullSpring(LocalModelBuilder& builder, Index vertex, double period) {
  SimObject& object = builder.object();
  const Index node = object.boundary().vertex_to_node[std::size_t(vertex)];
  // Outward normal: away from the centre of the object's nodes (only the model's push
  // direction depends on it; the stiffness does not).
  const Points& x = object.domain_positions();
  Vec3 normal = x.col(node) - x.rowwise().mean();
  normal = normal.norm() > 0 ? normal.normalized() : Vec3::UnitZ();
  LocalDynamicModel model;
  if (!builder.Build(vertex, normal, 0.0, period, model)) return std::nullopt;
  // K_c = (E' K^-1 E)^-1: the local stiffness condensed at the contact node (local dofs 0-2).
  const Eigen::MatrixXd k = model.stiffness.topLeftCorner(model.dofs(), model.dofs());
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(k);
  if (!lu.isInvertible()) return std::nullopt;
  const Eigen::MatrixXd compliance = lu.solve(Eigen::MatrixXd::Identity(k.rows(), 3));
  const Mat3 kc = compliance.topRows(3).inverse();
  const Eigen::SelfAdjointEigenSolver<Mat3> eigen(0.5 * (kc + kc.transpose()));
  const double lo = eigen.eigenvalues()(0), hi = eigen.eigenvalues()(2);
  const double delta = 0.2 * MeanEdgeLength(object.domain(), node);
  if (!(lo > 0) || !std::isfinite(hi) || !(delta > 0)) return std::nullopt;
  const double stiffness = 0.25 * lo, m = model.mass(0);
  const double damping = std::min(1.5 * stiffness * period, m > 0 ? 0.5 * m / period : 0.0);
  return PullSpring{stiffness, damping, hi * delta};
}

Vec3 PullForce(const PullSpring& spring, const Vec3& target, const Vec3& x, const Vec3& v) {
  const Vec3 f = spring.stiffness * (target - x) - spring.damping * v;
  const double norm = f.norm();
  return norm > spring.max_force ? f * (spring.max_force / norm) : f;
}

std::string PullTool::Grab(std::unique_ptr<LocalModelBuilder> builder, const Vec3& point,
                           double period) {
  Release();
  SimObject& object = builder->object();
  const BoundarySurface& boundary = object.boundary();
  const Points& x = object.domain_positions();
  const BoundaryConditions& bcs = object.boundary_conditions();
  const auto external = object.TryFindField("external_force");
  if (!external || !object.field_info(*external).writable() ||
      object.field_info(*external).location != FieldLocation::kNode)
    return fmt::format("object '{}' takes no external force", object.name());
  double nearest = std::numeric_limits<double>::infinity();
  Index vertex = -1;
  for (Index v = 0; v < boundary.num_vertices(); ++v) {
    if (bcs.kind(v, 0) != ConstraintKind::kFree || bcs.kind(v, 1) != ConstraintKind::kFree ||
        bcs.kind(v, 2) != ConstraintKind::kFree)
      continue;  // held by the scene: not ours to pull
    const double dist = (x.col(boundary.vertex_to_node[std::size_t(v)]) - point).squaredNorm();
    if (dist < nearest) {
      nearest = dist;
      vertex = v;
    }
  }
  if (vertex < 0) return fmt::format("every boundary node of '{}' is held", object.name());
  const auto spring = ScalePullSpring(*builder, vertex, period);
  if (!spring)
    return fmt::format("object '{}' offers no stiffness to pull against at the picked point",
                       object.name());
  builder_ = std::move(builder);
  vertex_ = vertex;
  node_ = boundary.vertex_to_node[std::size_t(vertex)];
  spring_ = *spring;
  picked_ = target_ = point;
  offset_ = x.col(node_) - point;
  moved_ = false;
  force_.setZero();
  last_x_ = x.col(node_);
  last_time_ = object.time();
  external_force_ = *external;
  loads_.resize(3, object.FieldCount(*external));
  return {};
}

void PullTool::MoveTo(const Vec3& target) {
  if (!active()) return;
  target_ = target;
  moved_ = moved_ || target != picked_;
}

void PullTool::Write(const Vec3& force) {
  SimObject& object = builder_->object();
  object.ReadField(external_force_, loads_);
  loads_.col(node_) += force - force_;  // replaces our previous contribution only
  object.WriteField(external_force_, loads_);
  force_ = force;
}

void PullTool::Apply() {
  if (!active()) return;
  const SimObject& object = builder_->object();
  const Vec3 x = object.domain_positions().col(node_);
  const double dt = object.time() - last_time_;
  const Vec3 v = dt > 0 ? Vec3((x - last_x_) / dt) : Vec3::Zero();
  last_x_ = x;
  last_time_ = object.time();
  if (moved_) Write(PullForce(spring_, target_ + offset_, x, v));
}

void PullTool::Release() {
  if (active()) Write(Vec3::Zero());
  builder_.reset();
  vertex_ = node_ = -1;
  force_.setZero();
  moved_ = false;
}

}  // namespace gipsi::viz
