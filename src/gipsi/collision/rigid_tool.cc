#include "gipsi/collision/rigid_tool.h"

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/collision/tool_surface.h"

namespace gipsi {

namespace {

std::shared_ptr<const Mesh> ToolMesh(const std::string& name, const RigidToolSpec& spec,
                                     std::shared_ptr<const Mesh> mesh) {
  if (spec.shape == RigidToolSpec::Shape::kMesh) {
    if (!mesh || mesh->num_triangles() == 0)
      throw InputError(fmt::format("tool '{}': a mesh tool needs a triangle mesh", name));
    return mesh;
  }
  const double length = spec.shape == RigidToolSpec::Shape::kCapsule ? spec.length : 0.0;
  if (spec.shape == RigidToolSpec::Shape::kCapsule && !(spec.length > 0))
    throw InputError(fmt::format("tool '{}': a capsule needs a positive length", name));
  return std::make_shared<const Mesh>(MakeCapsuleSurface(spec.radius, length, spec.segments));
}

}  // namespace

RigidTool::RigidTool(std::string name, const RigidToolSpec& spec, std::shared_ptr<const Mesh> mesh)
    : SimObject(std::move(name)), spec_(spec) {
  for (std::size_t i = 1; i < spec_.path.size(); ++i)
    if (!(spec_.path[i].first > spec_.path[i - 1].first))
      throw InputError(fmt::format("tool '{}': path times must increase strictly", this->path()));
  if (spec_.shape == RigidToolSpec::Shape::kSphere) spec_.length = 0;  // axis_end == start
  auto domain = ToolMesh(this->name(), spec_, std::move(mesh));
  Mesh surface_only = *domain;
  surface_only.tets.resize(4, 0);
  BoundarySurface boundary = MakeBoundary(surface_only);
  SetGeometry(domain, std::move(boundary));
  BindState(state_);
  using L = FieldLocation;
  using A = FieldAccess;
  f_position_ = DeclareField({"position", L::kNode, 3, "m", A::kRead, "current node position"});
  f_velocity_ = DeclareField({"velocity", L::kNode, 3, "m/s", A::kRead, "node velocity"});
  f_displacement_ =
      DeclareField({"displacement", L::kNode, 3, "m", A::kRead, "position minus rest position"});
  f_bposition_ = DeclareField({"boundary_position", L::kBoundaryVertex, 3, "m", A::kRead,
                               "current boundary vertex position"});
  f_bvelocity_ = DeclareField(
      {"boundary_velocity", L::kBoundaryVertex, 3, "m/s", A::kRead, "boundary vertex velocity"});
  f_bdisplacement_ = DeclareField({"boundary_displacement", L::kBoundaryVertex, 3, "m", A::kRead,
                                   "boundary vertex displacement"});
  f_force_ = DeclareField({"contact_force", L::kGlobal, 3, "N", A::kRead,
                           "sum of the contact forces on the tool this macro step"});
  f_offset_ = DeclareField(
      {"offset", L::kGlobal, 3, "m", A::kRead, "translation of the tool from its rest placement"});
  state_.offset = OffsetAt(0);
  Place();
}

Vec3 RigidTool::OffsetAt(double t) const {
  const auto& p = spec_.path;
  if (p.empty()) return spec_.velocity * t;
  if (t <= p.front().first) return p.front().second;
  if (t >= p.back().first) return p.back().second;
  std::size_t k = 1;
  while (p[k].first < t) ++k;
  const double w = (t - p[k - 1].first) / (p[k].first - p[k - 1].first);
  return (1 - w) * p[k - 1].second + w * p[k].second;
}

void RigidTool::Place() {
  positions_ = domain().nodes.colwise() + (spec_.position + state_.offset);
}

StepStatus RigidTool::DoStep(double t, double dt) {
  const Vec3 next = OffsetAt(t + dt);
  state_.velocity = (next - state_.offset) / dt;
  state_.offset = next;
  Place();
  return StepStatus::Ok();
}

Vec3 RigidTool::ContactForce() const {
  Vec3 f = Vec3::Zero();
  for (Index v = 0; v < boundary().num_vertices(); ++v) f += boundary_conditions().force(v);
  return f;
}

void RigidTool::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  const auto& v2n = boundary().vertex_to_node;
  if (id == f_position_) {
    out = positions_;
  } else if (id == f_velocity_) {
    out.colwise() = state_.velocity;
  } else if (id == f_displacement_) {
    out = positions_ - domain().nodes;
  } else if (id == f_bposition_ || id == f_bdisplacement_) {
    for (std::size_t j = 0; j < v2n.size(); ++j) {
      const Index n = v2n[j];
      out.col(static_cast<Index>(j)) = id == f_bposition_
                                           ? Vec3(positions_.col(n))
                                           : Vec3(positions_.col(n) - domain().nodes.col(n));
    }
  } else if (id == f_bvelocity_) {
    out.colwise() = state_.velocity;
  } else if (id == f_force_) {
    out.col(0) = ContactForce();
  } else if (id == f_offset_) {
    out.col(0) = state_.offset;
  }
}

void RigidTool::DoWriteField(FieldId /*id*/, const Eigen::Ref<const Eigen::MatrixXd>& /*in*/) {
  GIPSI_CHECK(false, "RigidTool has no writable field");
}

void RegisterRigidTool(TypeRegistry& registry) {
  registry.objects.Register(
      "RigidTool",
      [](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        const JsonNode& p = ctx.params;
        ctx.CheckKeys({"shape", "radius", "length", "segments", "position", "path", "velocity"});
        RigidToolSpec spec;
        const std::string shape = p.At("shape").AsChoice({"sphere", "capsule", "mesh"});
        std::shared_ptr<const Mesh> mesh;
        if (shape == "mesh") {
          spec.shape = RigidToolSpec::Shape::kMesh;
          for (const char* key : {"radius", "length", "segments"})
            if (p.Has(key)) p.At(key).Fail("only sphere and capsule tools have this key");
          mesh = ctx.DomainMesh();
          if (mesh->num_triangles() == 0) p.At("domain").Expected("a mesh with triangles");
        } else {
          if (p.Has("domain")) p.At("domain").Fail("a sphere or capsule tool makes its own mesh");
          spec.shape =
              shape == "sphere" ? RigidToolSpec::Shape::kSphere : RigidToolSpec::Shape::kCapsule;
          spec.radius = p.Positive("radius");
          if (shape == "capsule") {
            spec.length = p.Positive("length");
          } else if (p.Has("length")) {
            p.At("length").Fail("a sphere has no length (use shape \"capsule\")");
          }
          const std::int64_t segments = p.Int("segments", 16);
          if (segments < 4 || segments > 256) p.At("segments").Expected("an integer in [4, 256]");
          spec.segments = static_cast<int>(segments);
        }
        spec.position = p.Vector3("position", Vec3::Zero());
        if (p.Has("path") && p.Has("velocity"))
          p.At("velocity").Fail("give either 'path' or 'velocity', not both");
        if (auto path = p.Find("path")) {
          if (!path->is_array() || path->size() == 0)
            path->Expected("an array of [t, dx, dy, dz] keyframes");
          for (const JsonNode& key : path->Items()) {
            const std::vector<double> k = key.AsNumbers();
            if (k.size() != 4) key.Expected("[t, dx, dy, dz]");
            if (!spec.path.empty() && !(k[0] > spec.path.back().first))
              key.Fail("keyframe times must increase strictly");
            spec.path.emplace_back(k[0], Vec3(k[1], k[2], k[3]));
          }
        }
        spec.velocity = p.Vector3("velocity", Vec3::Zero());
        return std::make_unique<RigidTool>(ctx.name, spec, mesh);
      },
      "rigid tool (sphere, capsule or triangle mesh) moved along a scripted path");
}

}  // namespace gipsi
