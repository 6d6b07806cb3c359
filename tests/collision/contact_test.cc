#include "gipsi/collision/contact.h"

#include <cmath>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/collision/rigid_tool.h"
#include "gipsi/collision/tool_surface.h"
#include "gipsi/geometry/enclosed_volume.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/mass_spring/mass_spring.h"
#include "test_paths.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

std::unique_ptr<MassSpring> Block(const std::string& name, const Vec3& lo, const Vec3& hi,
                                  int cells) {
  MassSpringParams params;
  params.gravity.setZero();
  return std::make_unique<MassSpring>(
      name, std::make_shared<const Mesh>(MakeTetBox(lo, hi, {cells, cells, cells})), params,
      std::make_unique<SymplecticEuler>());
}

Vec3 TotalBoundaryForce(const SimObject& o) {
  Vec3 f = Vec3::Zero();
  for (Index v = 0; v < o.boundary().num_vertices(); ++v) f += o.boundary_conditions().force(v);
  return f;
}

Vec3 TotalBoundaryTorque(const SimObject& o, const Points& x) {
  Vec3 m = Vec3::Zero();
  for (Index v = 0; v < o.boundary().num_vertices(); ++v)
    m += Vec3(x.col(o.boundary().vertex_to_node[static_cast<std::size_t>(v)]))
             .cross(o.boundary_conditions().force(v));
  return m;
}

TEST(PenaltyForce, FollowsTheDocumentedLaw) {
  ContactMaterial m;
  m.thickness = 0.01;
  m.stiffness = 1000;
  m.damping = 5;
  m.friction = 0.5;
  m.slip_velocity = 1e-3;
  const Vec3 n(0, 0, 1);
  EXPECT_EQ(PenaltyForce(m, 0.01, n, Vec3::Zero()), Vec3::Zero());  // at the thickness
  EXPECT_EQ(PenaltyForce(m, 0.02, n, Vec3::Zero()), Vec3::Zero());
  // k (d − g) along n; approaching (v_n = −0.1) adds c · 0.1.
  EXPECT_NEAR((PenaltyForce(m, 0.004, n, Vec3::Zero()) - Vec3(0, 0, 6)).norm(), 0, 1e-12);
  EXPECT_NEAR(PenaltyForce(m, 0.004, n, Vec3(0, 0, -0.1)).z(), 6.5, 1e-12);
  // Fast separation: damping would pull; the force is clamped to zero.
  EXPECT_EQ(PenaltyForce(m, 0.004, n, Vec3(0, 0, 10)), Vec3::Zero());
  // Sliding well above the slip velocity: friction ≈ μ f_n against the slip.
  const Vec3 f = PenaltyForce(m, 0.004, n, Vec3(1, 0, 0));
  EXPECT_NEAR(f.z(), 6, 1e-12);
  EXPECT_NEAR(f.x(), -0.5 * 6 / std::sqrt(1 + 1e-6), 1e-12);
  EXPECT_EQ(f.y(), 0);
}

TEST(ToolSurface, CapsuleIsClosedAndOutward) {
  // The enclosed volume of the tessellation approaches the capsule's from below (inscribed).
  const double r = 0.1, L = 0.3;
  Mesh m = MakeCapsuleSurface(r, L, 48);
  const double exact = M_PI * r * r * L + 4.0 / 3.0 * M_PI * r * r * r;
  const double vol = EnclosedVolume(m.triangles, m.num_nodes()).Compute(m.nodes);
  EXPECT_GT(vol, 0.98 * exact);  // 48 segments: the inscribed polygon loses < 1 %, rings < 1 %
  EXPECT_LT(vol, exact);
  EXPECT_THROW(MakeCapsuleSurface(-1, 0, 8), InputError);
}

TEST(Contact, ForcesAreEqualAndOpposite) {
  // Two boxes overlapping the contact layer (gap 0.003 < thickness 0.005), shifted so that
  // their grids do not line up, with random boundary velocities and friction: every contact
  // gives the two bodies opposite forces, so the totals cancel.
  auto a = Block("a", Vec3(0, 0, 0), Vec3(1, 1, 1), 4);
  auto b = Block("b", Vec3(0.31, 0.17, 1.003), Vec3(1.21, 0.97, 1.8), 3);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  for (MassSpring* o : {a.get(), b.get()}) {
    Eigen::MatrixXd v(3, o->num_nodes());
    for (Index i = 0; i < v.size(); ++i) v.data()[i] = u(rng);
    o->WriteField(o->FindField("velocity"), v);
  }
  ContactMaterial m;
  m.thickness = 0.005;
  m.stiffness = 1000;
  m.damping = 3;
  m.friction = 0.4;
  Contact contact("c", {a.get(), b.get()}, m, {});
  ASSERT_TRUE(contact.Fire(0).ok());
  EXPECT_GT(contact.stats().vertex_contacts, 10);
  EXPECT_GT(contact.stats().edge_contacts, 10);
  const Vec3 fa = TotalBoundaryForce(*a), fb = TotalBoundaryForce(*b);
  EXPECT_LT(fa.z(), -1.0);  // a is below b: pushed down
  EXPECT_LT((fa + fb).norm(), 1e-12 * fa.norm());
}

TEST(Contact, FrictionlessContactExertsNoNetTorque) {
  // Without friction every contact force is along the line joining the two closest points, so
  // the pair of forces has no moment: the total torque on both bodies cancels.
  auto a = Block("a", Vec3(0, 0, 0), Vec3(1, 1, 1), 3);
  auto b = Block("b", Vec3(0.31, 0.17, 1.002), Vec3(1.21, 0.97, 1.8), 4);
  ContactMaterial m;
  m.thickness = 0.005;
  m.stiffness = 1000;
  Contact contact("c", {a.get(), b.get()}, m, {});
  ASSERT_TRUE(contact.Fire(0).ok());
  const Vec3 ta = TotalBoundaryTorque(*a, a->domain_positions());
  const Vec3 tb = TotalBoundaryTorque(*b, b->domain_positions());
  EXPECT_GT(ta.norm(), 1e-3);
  EXPECT_LT((ta + tb).norm(), 1e-12 * ta.norm());
  // And the push is along z: a is pushed down, b up.
  EXPECT_LT(TotalBoundaryForce(*a).z(), 0);
  EXPECT_GT(TotalBoundaryForce(*b).z(), 0);
}

TEST(Contact, SphereToolPushesWithThePenaltyLaw) {
  // A sphere tool of radius 2 whose centre is 1.995 above the top face of a block: vertices
  // of the top face within the thickness (0.02) of the sphere get k (d − gap) along the
  // radial direction, and the tool receives the opposite total.
  auto block = Block("block", Vec3(0, 0, 0), Vec3(1, 1, 1), 4);
  RigidToolSpec spec;
  spec.radius = 2;
  spec.position = Vec3(0.5, 0.5, 2.995);
  RigidTool tool("probe", spec, nullptr);
  ContactMaterial m;
  m.thickness = 0.02;
  m.stiffness = 100;
  Contact contact("c", {block.get(), &tool}, m, {});
  ASSERT_TRUE(contact.Fire(0).ok());
  Vec3 expected_total = Vec3::Zero();
  int touching = 0;
  const Points& x = block->domain_positions();
  for (Index v = 0; v < block->boundary().num_vertices(); ++v) {
    const Vec3 p = x.col(block->boundary().vertex_to_node[static_cast<std::size_t>(v)]);
    const double gap = (p - spec.position).norm() - spec.radius;
    const Vec3 want =
        gap < m.thickness
            ? Vec3(m.stiffness * (m.thickness - gap) * (p - spec.position).normalized())
            : Vec3::Zero();
    touching += gap < m.thickness;
    EXPECT_LT((block->boundary_conditions().force(v) - want).norm(), 1e-12) << v;
    expected_total += want;
  }
  // The centre vertex of the top face (gap −0.005) and its 4 neighbours 0.25 away (gap
  // sqrt(0.25² + 1.995²) − 2 = 0.0106); the diagonal ones have gap 0.026 > 0.02.
  EXPECT_EQ(touching, 5);
  EXPECT_LT((tool.ContactForce() + expected_total).norm(), 1e-12);
  Eigen::MatrixXd f(3, 1);
  tool.ReadField(tool.FindField("contact_force"), f);
  EXPECT_LT((Vec3(f.col(0)) + expected_total).norm(), 1e-12);
}

/// A plugin-style instrument: not a RigidTool, but a sphere offering the RigidCollider
/// capability (its boundary is the same tessellated sphere a RigidTool would have).
class Pointer final : public SimObject, public RigidCollider {
 public:
  Pointer(std::string name, const Vec3& centre, double radius)
      : SimObject(std::move(name)), centre_(centre), radius_(radius) {
    Mesh surface = MakeCapsuleSurface(radius, 0, 16);
    surface.nodes.colwise() += centre;
    auto mesh = std::make_shared<const Mesh>(surface);
    SetGeometry(mesh, MakeBoundary(*mesh));
    position_ = DeclareField({"boundary_position", FieldLocation::kBoundaryVertex, 3, "m",
                              FieldAccess::kRead, "vertex position"});
    velocity_ = DeclareField({"boundary_velocity", FieldLocation::kBoundaryVertex, 3, "m/s",
                              FieldAccess::kRead, "vertex velocity"});
  }
  std::string_view type_name() const override { return "Pointer"; }
  const Points& domain_positions() const override { return domain().nodes; }
  std::optional<Capsule> ExactCapsule() const override {
    return Capsule{centre_, centre_, radius_};
  }
  Vec3 RigidVelocity() const override { return Vec3::Zero(); }

 protected:
  StepStatus DoStep(double, double) override { return StepStatus::Ok(); }
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override {
    if (id == position_) {
      Points x;
      boundary().Gather(domain().nodes, x);
      out = x;
    } else {
      out.setZero();
    }
  }
  void DoWriteField(FieldId, const Eigen::Ref<const Eigen::MatrixXd>&) override {}

 private:
  Vec3 centre_;
  double radius_;
  FieldId position_, velocity_;
};

TEST(Contact, AnyRigidColliderIsATool) {
  // The same sphere as a RigidTool and as a foreign type with the RigidCollider capability:
  // Contact treats both as tools (exact sphere), so the block gets the same forces, bit for bit.
  ContactMaterial m;
  m.thickness = 0.02;
  m.stiffness = 100;
  const Vec3 centre(0.5, 0.5, 2.995);
  auto with_tool = Block("block", Vec3(0, 0, 0), Vec3(1, 1, 1), 4);
  RigidToolSpec spec;
  spec.radius = 2;
  spec.position = centre;
  RigidTool tool("probe", spec, nullptr);
  Contact by_tool("c", {with_tool.get(), &tool}, m, {});
  ASSERT_TRUE(by_tool.Fire(0).ok());
  auto with_pointer = Block("block", Vec3(0, 0, 0), Vec3(1, 1, 1), 4);
  Pointer pointer("pointer", centre, 2);
  Contact by_pointer("c", {with_pointer.get(), &pointer}, m, {});
  ASSERT_TRUE(by_pointer.Fire(0).ok());
  EXPECT_EQ(by_pointer.stats().tool_contacts, 5);
  EXPECT_EQ(by_pointer.stats().vertex_contacts, 0);  // no mesh pair: the exact sphere
  for (Index v = 0; v < with_tool->boundary().num_vertices(); ++v)
    EXPECT_EQ(with_pointer->boundary_conditions().force(v),
              with_tool->boundary_conditions().force(v))
        << v;
  // Its ports say so.
  bool calls = false;
  for (const PortUse& port : by_pointer.ports())
    calls = calls || (port.kind == PortUse::Kind::kCapability && port.object == &pointer &&
                      port.name == "rigid collider");
  EXPECT_TRUE(calls);
}

TEST(Contact, ProjectionHoldsVerticesOnTheToolAndBalancesTheBase) {
  // A sphere (radius 0.3) indents a mass-spring block (1 x 1 x 0.5, bottom fixed, no gravity)
  // by 0.09 and holds. With position projection no vertex ends inside the sphere, and at rest
  // the force on the tool equals the reaction at the fixed base (the block is in equilibrium
  // between the two sets of kinematic constraints).
  MassSpringParams params;
  params.gravity.setZero();
  params.stiffness = 500;
  params.density = 10;
  params.drag = 50;
  MassSpring block(
      "block", std::make_shared<const Mesh>(MakeTetBox(Vec3::Zero(), Vec3(1, 1, 0.5), {6, 6, 3})),
      params, std::make_unique<SymplecticEuler>());
  const Points& rest = block.domain().nodes;
  const auto& v2n = block.boundary().vertex_to_node;
  std::vector<int> base;
  for (std::size_t j = 0; j < v2n.size(); ++j)
    if (rest(2, v2n[j]) == 0) {
      block.boundary_conditions().Fix(static_cast<Index>(j));
      base.push_back(static_cast<int>(j));
    }
  RigidToolSpec spec;
  spec.radius = 0.3;
  spec.position = Vec3(0.5, 0.5, 0.81);
  spec.path = {{0.0, Vec3::Zero()}, {1.0, Vec3(0, 0, -0.1)}};
  RigidTool tool("probe", spec, nullptr);
  ContactMaterial m;
  m.thickness = 0.01;
  ContactOptions options;
  options.tool_response = ContactOptions::ToolResponse::kProjection;
  Contact contact("c", {&block, &tool}, m, options);
  const double dt = 0.002;
  for (int k = 0; k < 1500; ++k) {
    block.BeginMacroStep();
    tool.BeginMacroStep();
    ASSERT_TRUE(contact.Fire(k * dt).ok());
    ASSERT_TRUE(block.Step(dt).ok());
    ASSERT_TRUE(tool.Step(dt).ok());
  }
  block.BeginMacroStep();  // clears the coupling loads of the last step, as the kernel does
  tool.BeginMacroStep();
  ASSERT_TRUE(contact.Fire(1500 * dt).ok());
  // The centre vertex of the top face and its 4 neighbours (1/6 away; the contact radius
  // sqrt(2 · 0.3 · 0.09) = 0.23 reaches no diagonal vertex at 0.236).
  EXPECT_EQ(contact.stats().projected, 5);
  const Vec3 centre = tool.axis_start();
  for (std::size_t j = 0; j < v2n.size(); ++j)
    EXPECT_GT((Vec3(block.domain_positions().col(v2n[j])) - centre).norm(), 0.3 - 1e-12) << j;
  Eigen::MatrixXd reactions(3, block.boundary().num_vertices());
  block.ReadField(block.FindField("reaction_force"), reactions);
  Vec3 base_reaction = Vec3::Zero();
  for (int j : base) base_reaction += reactions.col(j);
  const Vec3 tool_force = tool.ContactForce();
  EXPECT_GT(tool_force.z(), 1.0);  // the tissue pushes the tool up
  // The slowest mode of this light block relaxes in ≈ 0.02 s under drag 50 1/s: after 2 s of
  // holding it is at rest to far better than 0.1 %.
  EXPECT_LT((tool_force - base_reaction).norm(), 1e-3 * tool_force.norm());
}

TEST(Contact, MeshToolForcesAreEqualAndOpposite) {
  // A rigid plate (a triangle-mesh tool) 3 mm above a block's top face, thickness 5 mm: the
  // block's top vertices touch the plate and the plate's vertices touch the block; the tool
  // receives exactly the opposite of what the block receives.
  auto block = Block("block", Vec3(0, 0, 0), Vec3(1, 1, 1), 4);
  auto plate = std::make_shared<const Mesh>(
      MakeTriangleSheet(Vec3(0.13, 0.21, 0), Vec3(0.6, 0, 0), Vec3(0, 0.5, 0), {5, 4}));
  RigidToolSpec spec;
  spec.shape = RigidToolSpec::Shape::kMesh;
  spec.position = Vec3(0, 0, 1.003);
  RigidTool tool("plate", spec, plate);
  ContactMaterial m;
  m.thickness = 0.005;
  m.stiffness = 100;
  Contact contact("c", {block.get(), &tool}, m, {});
  ASSERT_TRUE(contact.Fire(0).ok());
  EXPECT_GT(contact.stats().vertex_contacts, 20);
  const Vec3 f_block = TotalBoundaryForce(*block);
  EXPECT_LT(f_block.z(), -1.0);  // pushed down
  EXPECT_LT((tool.ContactForce() + f_block).norm(), 1e-12 * f_block.norm());
}

TEST(RigidTool, FollowsItsPathAndReportsItsVelocity) {
  RigidToolSpec spec;
  spec.shape = RigidToolSpec::Shape::kCapsule;
  spec.radius = 0.01;
  spec.length = 0.1;
  spec.path = {{0.0, Vec3::Zero()}, {1.0, Vec3(0, 0, -0.1)}, {2.0, Vec3(0.1, 0, -0.1)}};
  RigidTool tool("probe", spec, nullptr);
  for (int k = 0; k < 15; ++k) ASSERT_TRUE(tool.Step(0.1).ok());
  EXPECT_LT((tool.offset() - Vec3(0.05, 0, -0.1)).norm(), 1e-12);
  EXPECT_LT((tool.velocity() - Vec3(0.1, 0, 0)).norm(), 1e-9);
  EXPECT_LT((tool.axis_end() - tool.axis_start() - Vec3(0, 0, 0.1)).norm(), 1e-15);
}

std::string DropScene(const std::string& contact_extra = "") {
  // An upper block (6 cm, 0.216 kg) starts 5 mm above the middle of a lower block (10 cm)
  // whose bottom is fixed; both are mass-spring blocks of 3x3x3 cells, so their grids do not
  // line up. The contact fires every 0.1 ms step. Friction holds the block where it lands
  // (without it, the tilted normals at the rim of the contact patch let it creep sideways).
  // The slip velocity keeps the explicit friction stable: its viscous slope μ f_n / ε times
  // dt must stay well below a rim vertex's mass (0.5 · 0.13 N / 0.05 m/s · 1e-4 s ≈ 1.3e-4 kg
  // against ≈ 5e-4 kg); with ε = 1e-3 m/s it jitters.
  return R"({
  "units": "SI",
  "meshes": {
    "lower": {"generate": "box", "min": [0, 0, 0], "max": [0.1, 0.1, 0.1], "cells": [3, 3, 3]},
    "upper": {"generate": "box", "min": [0.021, 0.017, 0.105], "max": [0.081, 0.077, 0.165], "cells": [3, 3, 3]}
  },
  "objects": {
    "lower": {"type": "MassSpring", "domain": "lower", "stiffness": 2000, "damping": 2, "drag": 20,
              "boundary_conditions": [{"name": "floor", "region": {"group": "zmin"}, "fix": true}]},
    "upper": {"type": "MassSpring", "domain": "upper", "stiffness": 2000, "damping": 2, "drag": 20}
  },
  "connectors": {
    "contact": {"type": "Contact", "objects": ["lower", "upper"], "thickness": 0.002,
                "stiffness": 2000, "damping": 2, "friction": 0.5,
                "slip_velocity": 0.05)" +
         contact_extra + R"(}
  },
  "schedule": {"end": 1.0, "dt": 0.0001}
})";
}

TEST(Contact, DroppedBlockComesToRestOnTheFixedBlock) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(DropScene(), "drop.json", ".", registry);
  const RunResult run = scene.kernel->Run(1.0);
  ASSERT_TRUE(run.ok()) << run.diagnostic;
  const auto& contact = dynamic_cast<const Contact&>(scene.kernel->coordinator().connector(0));
  auto& upper = dynamic_cast<MassSpring&>(scene.kernel->FindObject("upper"));
  auto& lower = dynamic_cast<MassSpring&>(scene.kernel->FindObject("lower"));
  // At rest the contact carries the upper block's weight m g. After 20 drag time constants
  // (drag 20 1/s, 1 s) the residual motion is far below 0.1 % of it.
  const double weight = upper.masses().sum() * 9.81;
  EXPECT_NEAR(upper.masses().sum(), 0.216, 1e-12);
  EXPECT_NEAR(TotalBoundaryForce(upper).z(), weight, 1e-3 * weight);
  EXPECT_NEAR(TotalBoundaryForce(lower).z(), -weight, 1e-3 * weight);
  // At rest up to the creep the regularised friction allows (speed ≪ slip velocity): 1e-8 J
  // is 0.3 mm/s for this block.
  EXPECT_LT(upper.KineticEnergy(), 1e-8);
  // No interpenetration: every contact keeps a positive gap, and the lowest point of the upper
  // block stays above the highest point of the lower one (the upper block rests wholly on the
  // lower one's top face, which sags least under it).
  EXPECT_GT(contact.stats().min_gap, 0);
  EXPECT_LT(contact.stats().max_penetration, 0.002);
  const double upper_bottom = upper.domain_positions().row(2).minCoeff();
  const double lower_top = lower.domain_positions().row(2).maxCoeff();
  EXPECT_GT(upper_bottom, lower_top);
  EXPECT_LT(upper_bottom - lower_top, 0.002);  // resting inside the contact layer
}

TEST(Contact, SceneErrorsNameThePath) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  auto error = [&](const std::string& text) -> std::string {
    try {
      (void)LoadSceneFromString(text, "drop.json", ".", registry);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_THAT(error(DropScene(R"(, "frction": 0.2)")), HasSubstr("drop.json: connectors.contact"));
  EXPECT_THAT(error(DropScene(R"(, "frction": 0.2)")), HasSubstr("friction"));
  // (Replaced, not appended: a second "friction" key is itself an error, a duplicate key.)
  std::string negative = DropScene();
  negative.replace(negative.find(R"("friction": 0.5)"), 15, R"("friction": -1)");
  EXPECT_THAT(error(negative),
              HasSubstr("connectors.contact.friction: expected a non-negative number"));
  EXPECT_THAT(error(DropScene(R"(, "rebuild_ratio": 0.5)")),
              HasSubstr("connectors.contact.rebuild_ratio: expected a number > 1"));
  std::string bad = DropScene();
  bad.replace(bad.find(R"(["lower", "upper"])"), 18, R"(["lower", "uper"])");
  EXPECT_THAT(error(bad), HasSubstr("connectors.contact.objects[1]: no object named 'uper'"));
  std::string one = DropScene();
  one.replace(one.find(R"(["lower", "upper"])"), 18, R"(["lower"])");
  EXPECT_THAT(error(one), HasSubstr("nothing to collide"));
}

}  // namespace
}  // namespace gipsi

namespace gipsi {
namespace {

TEST(CollisionScenes, ShippedScenesLoadAndRun) {
  for (const char* name : {"block_drop.json", "probe_indentation.json"}) {
    TypeRegistry registry;
    RegisterBuiltins(registry);
    Scene scene = LoadScene(std::string(GIPSI_SOURCE_DIR) + "/scenes/" + name, registry);
    const RunResult run = scene.kernel->Run(0.03);
    EXPECT_TRUE(run.ok()) << name << ": " << run.diagnostic;
  }
}

}  // namespace
}  // namespace gipsi
