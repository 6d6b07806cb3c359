#pragma once
/// @file
/// `Contact`: the collision connector. Each time it fires it reads the boundary positions and
/// velocities of its objects, refits their AABB trees, finds every contact closer than the
/// contact thickness — object–object (vertex–triangle both ways, edge–edge), tool–object
/// (exact sphere/capsule primitives, or the tool's mesh) and, optionally, self-contact — and
/// turns them into penalty forces with damping and regularised Coulomb friction (penalty.h).
/// The forces reach the objects as *coupling forces on their boundary vertices*
/// (BoundaryConditions::AddCouplingForce), the same boundary API every connector uses: models
/// never see contact. A force at a point inside a triangle or an edge is spread over its
/// vertices with the point's barycentric weights, and each contact gives the two bodies exactly
/// opposite forces.
///
/// Scene (under "connectors"): {"type": "Contact", "objects": ["a", "b", "probe"],
///   "thickness": 0.002, "stiffness": 500, "damping": 0.5, "friction": 0.3,
///   "tool_response": "penalty" | "projection",
///   "slip_velocity": 0.001, "self_collision": false, "edge_edge": true, "rebuild_ratio": 1.5}
/// Objects need the fields "boundary_position" and "boundary_velocity" and boundary triangles.
/// Forces are applied explicitly (held over the macro step): fire it at the objects' step
/// (schedule.dt = object dt) when the penalty stiffness is high.
/// Allocation: contact lists keep their capacity between firings, so a firing allocates only
/// when it finds more contacts than any earlier one (the Connector contract's "nothing" holds
/// after that warm-up).

#include <memory>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/collision/collision_surface.h"
#include "gipsi/collision/penalty.h"
#include "gipsi/collision/proximity.h"
#include "gipsi/core/connector.h"
#include "gipsi/core/registry.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Options besides the contact material. Plain struct with defaults.
struct ContactOptions {
  /// How sphere/capsule tools act on objects: penalty forces, or position projection (a
  /// vertex that enters the tool is prescribed onto the tool's surface, and released when its
  /// reaction stops pushing it away from the tool; the tool receives minus the reactions). Use
  /// projection for stiff or quasi-static (implicit) objects, where an explicit penalty would
  /// need a stiffness above the tissue's and then oscillates. Object–object contact is always
  /// penalty.
  enum class ToolResponse { kPenalty, kProjection };
  ToolResponse tool_response = ToolResponse::kPenalty;
  bool self_collision = false;  ///< also self-contacts of each deformable object
  bool edge_edge = true;        ///< edge–edge contacts between meshes
  double rebuild_ratio = 1.5;   ///< AabbTree rebuild threshold (> 1)
};

/// Counts from the last firing. Plain struct.
struct ContactStats {
  std::int64_t vertex_contacts = 0, edge_contacts = 0, tool_contacts = 0, self_contacts = 0;
  /// Vertices held on a tool's surface (projection response).
  std::int64_t projected = 0;
  /// Largest penetration into the contact layer, thickness − gap [m] (0 without contact).
  double max_penetration = 0;
  /// Smallest signed gap over all contacts [m] (thickness without contact); negative means the
  /// surfaces interpenetrate.
  double min_gap = 0;
};

/// What Contact carries from one firing to the next (a state value type,
/// gipsi/base/state_value.h): per object (in objects order), which boundary vertices the
/// projection response holds on a tool (1) or not (0); empty for tools and under the penalty
/// response. The constraints themselves are the objects' boundary conditions, saved with them;
/// forces, velocities and proximity results are recomputed by every firing.
struct ContactState {
  std::vector<std::vector<char>> held;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("held", s.held, Shape::kFixed);
  }
};

/// Not copyable or movable.
class Contact final : public Connector {
 public:
  /// An object with the RigidCollider capability (rigid_collider.h; e.g. a RigidTool) is a
  /// tool, every other one deformable. Throws InputError if an object lacks the boundary
  /// fields or triangles, a name repeats, or there is nothing to collide (one object without
  /// self-collision, or only tools).
  Contact(std::string name, const std::vector<SimObject*>& objects, const ContactMaterial& material,
          const ContactOptions& options);
  ~Contact() override;

  [[nodiscard]] std::string_view type_name() const override { return "Contact"; }
  [[nodiscard]] const ContactStats& stats() const { return stats_; }
  /// The state (bound with BindState: checkpoints and snapshots copy it).
  [[nodiscard]] const ContactState& state() const { return state_; }
  [[nodiscard]] const ContactMaterial& material() const { return material_; }
  /// Force each object received at the last firing (3 by boundary vertices), in objects order.
  [[nodiscard]] const Points& last_forces(std::size_t object) const;

 protected:
  StepStatus DoFire(double t) override;

 private:
  struct Body;
  void MeshPair(Body& a, Body& b, bool self);
  void ToolPair(Body& tool, Body& body);
  void ToolProjection(Body& tool, Body& body);
  void AddVertexTriangle(Body& a, Body& b, const VertexTriangleContact& c);

  ContactMaterial material_;
  ContactOptions options_;
  std::vector<std::unique_ptr<Body>> bodies_;
  ProximityQuery query_;
  ProximityResult result_;
  std::vector<PrimitiveContact> primitive_;
  ContactStats stats_;
  ContactState state_;
};

/// Registers the "Contact" connector.
void RegisterContact(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
