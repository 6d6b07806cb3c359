/// @file
/// An example third-party plugin. It is built as a separate shared library that GiPSi loads at
/// run time (scene key "plugins", or `gipsi run --plugin PATH`), and registers:
///  - object type "Oscillator": a point that moves as x(t) = center + amplitude·sin(2π f t),
///    exposing the global fields "position" (m) and "velocity" (m/s). It is solved in closed
///    form, so it also shows that an object need not use the framework's integrators;
///  - connector type "Follow": prescribes the velocity of every vertex of a boundary region of
///    an object to a global vector field of another (e.g. drive a tissue edge by an Oscillator).
/// Nothing here is known to the framework at compile time.

#include <cmath>
#include <memory>
#include <numbers>

#include "gipsi/base/error.h"
#include "gipsi/core/coordinator.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/geometry/region_json.h"

namespace example {

using Eigen::MatrixXd;

/// What an Oscillator carries from one step to the next (a state value type). Copyable. The
/// position is a function of time, so only the node is state.
struct OscillatorState {
  gipsi::Points position = gipsi::Points::Zero(3, 1);  // the one node [m]

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("position", s.position, gipsi::Shape::kFixed);
  }
};

class Oscillator final : public gipsi::SimObject {
 public:
  Oscillator(std::string name, const gipsi::Vec3& center, const gipsi::Vec3& amplitude,
             double frequency)
      : SimObject(std::move(name)), center_(center), amplitude_(amplitude), frequency_(frequency) {
    gipsi::Mesh mesh;
    mesh.nodes = center;
    SetGeometry(std::make_shared<const gipsi::Mesh>(std::move(mesh)), gipsi::BoundarySurface{});
    position_ = DeclareField({"position", gipsi::FieldLocation::kGlobal, 3, "m",
                              gipsi::FieldAccess::kRead, "current position"});
    velocity_ = DeclareField({"velocity", gipsi::FieldLocation::kGlobal, 3, "m/s",
                              gipsi::FieldAccess::kRead, "current velocity"});
    state_.position = center;
    // Checkpoints save, and step retries copy, this state (gipsi/base/state_value.h).
    BindState(state_);
  }
  std::string_view type_name() const override { return "Oscillator"; }
  const gipsi::Points& domain_positions() const override { return state_.position; }

 protected:
  gipsi::StepStatus DoStep(double t, double dt) override {
    state_.position = Position(t + dt);
    return gipsi::StepStatus::Ok();
  }
  void DoReadField(gipsi::FieldId id, Eigen::Ref<MatrixXd> out) const override {
    const double t = time();
    const double w = 2 * std::numbers::pi * frequency_;
    out.col(0) = id == position_ ? Position(t) : gipsi::Vec3(amplitude_ * w * std::cos(w * t));
  }
  void DoWriteField(gipsi::FieldId, const Eigen::Ref<const MatrixXd>&) override {}

 private:
  gipsi::Vec3 Position(double t) const {
    return center_ + amplitude_ * std::sin(2 * std::numbers::pi * frequency_ * t);
  }
  gipsi::Vec3 center_, amplitude_;
  double frequency_;
  gipsi::FieldId position_, velocity_;
  OscillatorState state_;
};

class Follow final : public gipsi::Connector {
 public:
  Follow(std::string name, gipsi::SimObject& source, gipsi::FieldId field, gipsi::SimObject& target,
         std::vector<int> vertices)
      : Connector(std::move(name)),
        source_(source),
        field_(field),
        target_(target),
        vertices_(std::move(vertices)),
        value_(3, 1) {
    // Its ports: the coordinator checks them before the first step, `gipsi validate` lists
    // them. The velocity is read in m/s and prescribed on the target's boundary.
    UseField("from", source, source.field_info(field).name, gipsi::FieldAccess::kRead, "m/s", 3);
    UseBoundaryConditions("to", target);
    // Its state: none. Follow only transfers values (the prescribed velocities are the
    // target's boundary conditions, saved with it), so checkpoints and retries copy nothing.
    BindNoState();
  }
  std::string_view type_name() const override { return "Follow"; }

 protected:
  gipsi::StepStatus DoFire(double) override {
    source_.ReadField(field_, value_);
    for (int v : vertices_) target_.boundary_conditions().PrescribeVelocity(v, value_.col(0));
    return gipsi::StepStatus::Ok();
  }

 private:
  gipsi::SimObject& source_;
  gipsi::FieldId field_;
  gipsi::SimObject& target_;
  std::vector<int> vertices_;
  MatrixXd value_;
};

}  // namespace example

extern "C" int gipsi_plugin_abi_version() { return GIPSI_PLUGIN_ABI_VERSION; }

extern "C" void gipsi_register_plugin(gipsi::TypeRegistry& registry) {
  registry.objects.Register(
      "Oscillator",
      [](const gipsi::ObjectBuildContext& ctx) -> std::unique_ptr<gipsi::SimObject> {
        ctx.CheckKeys({"center", "amplitude", "frequency"});
        return std::make_unique<example::Oscillator>(
            ctx.name, ctx.params.Vector3("center", gipsi::Vec3::Zero()),
            ctx.params.Vector3("amplitude"), ctx.params.Positive("frequency"));
      },
      "(example plugin) a point moving sinusoidally, in closed form");
  registry.connectors.Register(
      "Follow",
      [](const gipsi::ConnectorBuildContext& ctx) -> std::unique_ptr<gipsi::Connector> {
        ctx.CheckKeys({"from", "to", "region"});
        auto [source, field] = ctx.ObjectField("from");
        if (source->field_info(field).components != 3 ||
            source->field_info(field).location != gipsi::FieldLocation::kGlobal)
          ctx.params.At("from").Expected("a global vector field");
        gipsi::SimObject& target = ctx.Object("to");
        gipsi::Region region = gipsi::AllRegion{};
        if (auto r = ctx.params.Find("region")) region = gipsi::ParseRegion(*r);
        auto vertices = gipsi::SelectBoundaryVertices(region, target.domain(), target.boundary());
        if (vertices.empty()) ctx.params.Fail("the region selects no boundary vertex");
        return std::make_unique<example::Follow>(ctx.name, *source, field, target,
                                                 std::move(vertices));
      },
      "(example plugin) prescribe a boundary region's velocity from a global vector field");
}
