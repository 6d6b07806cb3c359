#include "gipsi/collision/contact.h"

#include <algorithm>
#include <optional>
#include <set>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/collision/rigid_collider.h"
#include "gipsi/core/coordinator.h"

namespace gipsi {

struct Contact::Body {
  SimObject& object;
  const RigidCollider* tool = nullptr;  // non-null for tools
  FieldId position, velocity;
  CollisionSurface surface;
  Points velocities;
  Points forces;
  // Projection response: the reaction field and its values (which vertices are held is the
  // state's held[index]).
  std::optional<FieldId> reaction;
  Points reactions;
  std::size_t index;  // in objects order
  Body(SimObject& o, const RigidCollider* t, FieldId p, FieldId v, CollisionSurface s,
       std::size_t i)
      : object(o), tool(t), position(p), velocity(v), surface(std::move(s)), index(i) {
    velocities.setZero(3, surface.num_vertices());
    forces.setZero(3, surface.num_vertices());
  }
  [[nodiscard]] bool primitive() const { return tool != nullptr && tool->ExactCapsule(); }
};

Contact::Contact(std::string name, const std::vector<SimObject*>& objects,
                 const ContactMaterial& material, const ContactOptions& options)
    : Connector(std::move(name)), material_(material), options_(options) {
  std::set<const SimObject*> seen;
  int deformables = 0;
  for (SimObject* o : objects) {
    GIPSI_CHECK(o != nullptr);
    if (!seen.insert(o).second)
      throw InputError(
          fmt::format("connector '{}': object '{}' is listed twice", this->path(), o->path()));
    const FieldId p = o->FindField("boundary_position");
    const FieldId v = o->FindField("boundary_velocity");
    const std::string key = fmt::format("objects[{}]", bodies_.size());
    UseField(key, *o, "boundary_position", FieldAccess::kRead, "m", 3);
    UseField(key, *o, "boundary_velocity", FieldAccess::kRead, "m/s", 3);
    UseBoundaryConditions(key, *o);
    const BoundarySurface& b = o->boundary();
    if (b.num_triangles() == 0)
      throw InputError(
          fmt::format("connector '{}': object '{}' has no boundary triangles to collide with",
                      this->path(), o->path()));
    const auto* tool = dynamic_cast<const RigidCollider*>(o);
    if (tool)
      UseCapability(key, *o, "rigid collider");
    else
      ++deformables;
    const bool closed = !b.face_to_tet.empty() && b.face_to_tet.front() >= 0;
    bodies_.push_back(std::make_unique<Body>(
        *o, tool, p, v, CollisionSurface(b.triangles, b.num_vertices(), closed), bodies_.size()));
    state_.held.emplace_back();
    if (!tool && options_.tool_response == ContactOptions::ToolResponse::kProjection) {
      bodies_.back()->reaction = o->FindField("reaction_force");
      UseField(key, *o, "reaction_force", FieldAccess::kRead, "N", 3);
      bodies_.back()->reactions.setZero(3, b.num_vertices());
      state_.held.back().assign(static_cast<std::size_t>(b.num_vertices()), 0);
    }
  }
  BindState(state_);
  if (deformables == 0 || (objects.size() < 2 && !options_.self_collision))
    throw InputError(fmt::format(
        "connector '{}': nothing to collide; list at least one deformable object and a second "
        "object or tool, or enable self_collision",
        this->path()));
}

Contact::~Contact() = default;

const Points& Contact::last_forces(std::size_t object) const { return bodies_.at(object)->forces; }

namespace {

// Signed gap and unit normal (toward the vertex) of a vertex at p whose closest point on
// triangle t of `s` is c (see proximity.h). Closed surfaces give a signed gap (negative
// inside, pushed out along the face normal); open ones are two-sided.
void VertexGap(const CollisionSurface& s, int t, const Vec3& p, const Vec3& c, double scale,
               double& gap, Vec3& normal) {
  const Vec3 diff = p - c;
  const double dist = diff.norm();
  const Vec3 face = s.face_normals().col(t);
  if (s.closed()) {
    const double sign = diff.dot(face) >= 0 ? 1.0 : -1.0;
    gap = sign * dist;
    normal = (sign > 0 && dist > 1e-12 * scale) ? Vec3(diff / dist) : face;
  } else {
    gap = dist;
    normal = dist > 1e-12 * scale ? Vec3(diff / dist) : face;
  }
}

}  // namespace

void Contact::AddVertexTriangle(Body& a, Body& b, const VertexTriangleContact& c) {
  double gap = 0;
  Vec3 n;
  const Vec3 p = a.surface.positions().col(c.vertex);
  VertexGap(b.surface, c.triangle, p, c.closest, material_.thickness, gap, n);
  const auto& tri = b.surface.triangles();
  Vec3 vb = Vec3::Zero();
  for (int k = 0; k < 3; ++k) vb += c.bary[k] * b.velocities.col(tri(k, c.triangle));
  const Vec3 f = PenaltyForce(material_, gap, n, Vec3(a.velocities.col(c.vertex)) - vb);
  a.forces.col(c.vertex) += f;
  for (int k = 0; k < 3; ++k) b.forces.col(tri(k, c.triangle)) -= c.bary[k] * f;
  stats_.max_penetration = std::max(stats_.max_penetration, material_.thickness - gap);
  stats_.min_gap = std::min(stats_.min_gap, gap);
}

void Contact::MeshPair(Body& a, Body& b, bool self) {
  if (self) {
    query_.QuerySelf(a.surface, material_.thickness, options_.edge_edge, result_);
    stats_.self_contacts += static_cast<std::int64_t>(result_.size());
  } else {
    query_.Query(a.surface, b.surface, material_.thickness, options_.edge_edge, result_);
    stats_.vertex_contacts +=
        static_cast<std::int64_t>(result_.a_on_b.size() + result_.b_on_a.size());
    stats_.edge_contacts += static_cast<std::int64_t>(result_.edges.size());
  }
  for (const auto& c : result_.a_on_b) AddVertexTriangle(a, b, c);
  for (const auto& c : result_.b_on_a) AddVertexTriangle(b, a, c);
  const auto& ea = a.surface.edges();
  const auto& eb = b.surface.edges();
  for (const auto& e : result_.edges) {
    const int a0 = ea(0, e.edge_a), a1 = ea(1, e.edge_a);
    const int b0 = eb(0, e.edge_b), b1 = eb(1, e.edge_b);
    const Vec3 pa = (1 - e.s) * a.surface.positions().col(a0) + e.s * a.surface.positions().col(a1);
    const Vec3 pb = (1 - e.t) * b.surface.positions().col(b0) + e.t * b.surface.positions().col(b1);
    if (!(e.distance > 1e-12 * material_.thickness)) continue;  // no defined direction
    const Vec3 n = (pa - pb) / e.distance;
    const Vec3 va = (1 - e.s) * a.velocities.col(a0) + e.s * a.velocities.col(a1);
    const Vec3 vb = (1 - e.t) * b.velocities.col(b0) + e.t * b.velocities.col(b1);
    const Vec3 f = PenaltyForce(material_, e.distance, n, va - vb);
    a.forces.col(a0) += (1 - e.s) * f;
    a.forces.col(a1) += e.s * f;
    b.forces.col(b0) -= (1 - e.t) * f;
    b.forces.col(b1) -= e.t * f;
    stats_.max_penetration = std::max(stats_.max_penetration, material_.thickness - e.distance);
    stats_.min_gap = std::min(stats_.min_gap, e.distance);
  }
}

void Contact::ToolPair(Body& tool, Body& body) {
  const Capsule capsule = *tool.tool->ExactCapsule();
  const Vec3 tool_velocity = tool.tool->RigidVelocity();
  query_.QueryCapsule(body.surface, capsule.start, capsule.end, capsule.radius, material_.thickness,
                      primitive_);
  stats_.tool_contacts += static_cast<std::int64_t>(primitive_.size());
  const Points& tool_x = tool.surface.positions();
  for (const PrimitiveContact& c : primitive_) {
    const Vec3 f = PenaltyForce(material_, c.gap, c.normal,
                                Vec3(body.velocities.col(c.vertex)) - tool_velocity);
    body.forces.col(c.vertex) += f;
    // The reaction acts on the tool at the contact point; it is given to the tool's nearest
    // surface vertex (the total force is exact; its point of application is within one
    // tessellation cell).
    Index nearest = 0;
    (tool_x.colwise() - c.on_tool).colwise().squaredNorm().minCoeff(&nearest);
    tool.forces.col(nearest) -= f;
    stats_.max_penetration = std::max(stats_.max_penetration, material_.thickness - c.gap);
    stats_.min_gap = std::min(stats_.min_gap, c.gap);
  }
}

void Contact::ToolProjection(Body& tool, Body& body) {
  const Capsule capsule = *tool.tool->ExactCapsule();
  query_.QueryCapsule(body.surface, capsule.start, capsule.end, capsule.radius, material_.thickness,
                      primitive_);
  stats_.tool_contacts += static_cast<std::int64_t>(primitive_.size());
  BoundaryConditions& bcs = body.object.boundary_conditions();
  const auto& v2n = body.object.boundary().vertex_to_node;
  const Points& rest = body.object.domain().nodes;
  const Points& tool_x = tool.surface.positions();
  std::size_t k = 0;  // walks primitive_ (sorted by vertex) alongside the held flags
  for (Index v = 0; v < body.surface.num_vertices(); ++v) {
    const PrimitiveContact* c = nullptr;
    while (k < primitive_.size() && primitive_[k].vertex < v) ++k;
    if (k < primitive_.size() && primitive_[k].vertex == v) c = &primitive_[k];
    char& held = state_.held[body.index][static_cast<std::size_t>(v)];
    bool keep = false;
    if (c) {
      if (held) {
        // Held: keep while the reaction still pushes the vertex away from the tool.
        keep = Vec3(body.reactions.col(v)).dot(c->normal) > 0;
      } else {
        // Free: take it when it has entered the tool and nothing else constrains it.
        bool free = true;
        for (int a = 0; a < 3; ++a) free = free && bcs.kind(v, a) == ConstraintKind::kFree;
        keep = free && c->gap < 0;
      }
    }
    if (keep) {
      const Index node = v2n[static_cast<std::size_t>(v)];
      bcs.PrescribeDisplacement(v, c->on_tool - Vec3(rest.col(node)));
      if (held) {
        Index nearest = 0;
        (tool_x.colwise() - c->on_tool).colwise().squaredNorm().minCoeff(&nearest);
        tool.forces.col(nearest) -= body.reactions.col(v);
      }
      held = 1;
      ++stats_.projected;
    } else if (held) {
      bcs.Release(v);
      held = 0;
    }
  }
}

StepStatus Contact::DoFire(double /*t*/) {
  stats_ = ContactStats{};
  stats_.min_gap = material_.thickness;
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    Body& b = *bodies_[i];
    b.object.ReadField(b.position, b.surface.positions());
    b.object.ReadField(b.velocity, b.velocities);
    if (!b.surface.positions().allFinite() || !b.velocities.allFinite())
      return StepStatus::Diverged("non-finite boundary position or velocity in object",
                                  static_cast<Index>(i));
    b.surface.Update(options_.rebuild_ratio, options_.self_collision && b.tool == nullptr);
    b.forces.setZero();
    if (b.reaction) {
      b.object.ReadField(*b.reaction, b.reactions);
      if (!b.reactions.allFinite())
        return StepStatus::Diverged("non-finite reaction force in object", static_cast<Index>(i));
    }
  }
  const double d = material_.thickness;
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    for (std::size_t j = i + 1; j < bodies_.size(); ++j) {
      Body& a = *bodies_[i];
      Body& b = *bodies_[j];
      if (a.tool && b.tool) continue;
      if (!a.surface.bounds().Near(b.surface.bounds(), d)) continue;  // broad phase
      const bool project = options_.tool_response == ContactOptions::ToolResponse::kProjection;
      if (a.primitive()) {
        project ? ToolProjection(a, b) : ToolPair(a, b);
      } else if (b.primitive()) {
        project ? ToolProjection(b, a) : ToolPair(b, a);
      } else {
        MeshPair(a, b, false);
      }
    }
    if (options_.self_collision && bodies_[i]->tool == nullptr)
      MeshPair(*bodies_[i], *bodies_[i], true);
  }
  for (auto& body : bodies_) {
    BoundaryConditions& bcs = body->object.boundary_conditions();
    for (Index v = 0; v < body->forces.cols(); ++v)
      if (body->forces.col(v).squaredNorm() > 0) bcs.AddCouplingForce(v, body->forces.col(v));
  }
  return StepStatus::Ok();
}

void RegisterContact(TypeRegistry& registry) {
  registry.connectors.Register(
      "Contact",
      [](const ConnectorBuildContext& ctx) -> std::unique_ptr<Connector> {
        const JsonNode& p = ctx.params;
        ctx.CheckKeys({"objects", "thickness", "stiffness", "damping", "friction", "slip_velocity",
                       "self_collision", "edge_edge", "rebuild_ratio", "tool_response"});
        const JsonNode list = p.At("objects");
        if (!list.is_array() || list.size() == 0) list.Expected("an array of object names");
        std::vector<SimObject*> objects;
        for (const JsonNode& item : list.Items()) {
          const std::string name = item.AsString();
          SimObject* o = ctx.scope.FindObject(name);
          if (!o)
            item.Fail(fmt::format("no object named '{}'{}", name,
                                  SuggestClosest(name, ctx.scope.ObjectNames())));
          objects.push_back(o);
        }
        ContactMaterial m;
        m.thickness = p.Positive("thickness");
        m.stiffness = p.Positive("stiffness");
        m.damping = p.NonNegative("damping", 0.0);
        m.friction = p.NonNegative("friction", 0.0);
        m.slip_velocity = p.Positive("slip_velocity", m.slip_velocity);
        ContactOptions o;
        if (auto r = p.Find("tool_response"))
          o.tool_response = r->AsChoice({"penalty", "projection"}) == "projection"
                                ? ContactOptions::ToolResponse::kProjection
                                : ContactOptions::ToolResponse::kPenalty;
        o.self_collision = p.Bool("self_collision", false);
        o.edge_edge = p.Bool("edge_edge", true);
        o.rebuild_ratio = p.Number("rebuild_ratio", o.rebuild_ratio);
        if (!(o.rebuild_ratio > 1)) p.At("rebuild_ratio").Expected("a number > 1");
        try {
          return std::make_unique<Contact>(ctx.name, objects, m, o);
        } catch (const InputError& e) {
          p.Fail(e.what());
        }
      },
      "collision: penalty contact (damping, friction) between objects and tools, as boundary "
      "forces");
}

}  // namespace gipsi
