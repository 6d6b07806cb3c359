// An outside user's program, built against the installed GiPSi package (find_package(gipsi)):
// it sees only the installed headers and libraries, never GiPSi's source tree.
//
// It adds two types of its own and checks the framework runs them:
//  - object type "ThermalNode": a lumped heat capacity C [J/K] at temperature T [K] with
//    dT/dt = q / C, q the heat flowing in [W] (a field other objects' connectors write). It
//    states its ODE and is stepped by a framework integrator chosen by name ("RK4" by default);
//  - connector type "Conductor": a thermal conductance G [W/K] between two nodes, writing
//    q = G (T_b - T_a) into a and -q into b, and keeping the heat it has passed (its own state,
//    saved in checkpoints).
// The scene is built as JSON in code, loaded with the built-in types plus these two, and run.
//
// Checks (exit 1 on any failure, with what differs):
//  1. Energy: C_a T_a + C_b T_b is conserved to rounding (1e-12 relative).
//  2. The difference d = T_a - T_b follows the staggered scheme exactly: with q fixed over a
//     macro step, RK4 integrates dT/dt = q/C exactly, so d_{n+1} = d_n (1 - G dt (1/C_a + 1/C_b)).
//  3. The heat the conductor counted equals C_a (T_a(0) - T_a(t)).
//  4. A checkpoint written half-way and restored into a freshly loaded scene ends bitwise equal.
//  5. A bad parameter of the new type is refused with the JSON path of the value.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "gipsi/base/error.h"
#include "gipsi/core/connector.h"
#include "gipsi/core/kernel.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/numerics/ode.h"

namespace thermal {

/// What a ThermalNode carries from one step to the next: its temperature.
struct ThermalState {
  gipsi::VecX temperature = gipsi::VecX::Zero(1);  // [K]

  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("temperature", s.temperature, gipsi::Shape::kFixed);
  }
};

class ThermalNode final : public gipsi::SimObject {
 public:
  ThermalNode(std::string name, double capacity, double temperature,
              std::unique_ptr<gipsi::OdeIntegrator> integrator)
      : SimObject(std::move(name)), capacity_(capacity), integrator_(std::move(integrator)) {
    SetGeometry(std::make_shared<const gipsi::Mesh>(), gipsi::BoundarySurface{});
    temperature_ = DeclareField({"temperature", gipsi::FieldLocation::kGlobal, 1, "K",
                                 gipsi::FieldAccess::kRead, "temperature"});
    heat_in_ = DeclareField({"heat_in", gipsi::FieldLocation::kGlobal, 1, "W",
                             gipsi::FieldAccess::kWrite, "heat flowing in"});
    state_.temperature[0] = temperature;
    BindState(state_);  // checkpoints and step retries use it
    integrator_->Prepare(1);
  }
  std::string_view type_name() const override { return "ThermalNode"; }
  const gipsi::Points& domain_positions() const override { return no_positions_; }

  // The ODE contract (gipsi/numerics/ode.h).
  gipsi::Index ode_size() const { return 1; }
  gipsi::Index ode_num_positions() const { return 0; }
  void CalcDerivative(double, Eigen::Ref<const gipsi::VecX>, Eigen::Ref<gipsi::VecX> d) const {
    d[0] = heat_in_value_ / capacity_;
  }

 protected:
  gipsi::StepStatus DoStep(double t, double dt) override {
    if (!integrator_->Step(gipsi::OdeView(*this), t, dt, state_.temperature))
      return gipsi::StepStatus::Failed("the integrator failed");
    return gipsi::StepStatus::Ok();
  }
  void DoReadField(gipsi::FieldId, Eigen::Ref<Eigen::MatrixXd> out) const override {
    out(0, 0) = state_.temperature[0];
  }
  void DoWriteField(gipsi::FieldId, const Eigen::Ref<const Eigen::MatrixXd>& in) override {
    heat_in_value_ = in(0, 0);
  }

 private:
  double capacity_;
  std::unique_ptr<gipsi::OdeIntegrator> integrator_;
  gipsi::FieldId temperature_, heat_in_;
  ThermalState state_;
  double heat_in_value_ = 0;  // an input, set by a connector before every step
  gipsi::Points no_positions_ = gipsi::Points(3, 0);
};

class Conductor final : public gipsi::Connector {
 public:
  Conductor(std::string name, gipsi::SimObject& a, gipsi::SimObject& b, double conductance)
      : Connector(std::move(name)), a_(a), b_(b), conductance_(conductance) {
    UseField("a", a, "temperature", gipsi::FieldAccess::kRead, "K", 1);
    UseField("b", b, "temperature", gipsi::FieldAccess::kRead, "K", 1);
    UseField("a", a, "heat_in", gipsi::FieldAccess::kWrite, "W", 1);
    UseField("b", b, "heat_in", gipsi::FieldAccess::kWrite, "W", 1);
    ta_ = a.FindField("temperature");
    tb_ = b.FindField("temperature");
    qa_ = a.FindField("heat_in");
    qb_ = b.FindField("heat_in");
  }
  std::string_view type_name() const override { return "Conductor"; }
  /// The heat that has flowed from a to b by time t >= the last fire [J].
  double HeatPassedBy(double t) const { return heat_passed_ + last_q_ * (t - last_fire_); }

  void SaveConnectorState(gipsi::StateWriter& out) const override {
    out.WriteDouble(heat_passed_);
    out.WriteDouble(last_fire_);
    out.WriteDouble(last_q_);
  }
  void RestoreConnectorState(gipsi::StateReader& in) override {
    heat_passed_ = in.ReadDouble();
    last_fire_ = in.ReadDouble();
    last_q_ = in.ReadDouble();
  }

 protected:
  gipsi::StepStatus DoFire(double t) override {
    // The heat of the last interval at the flow it had (the flow is held over a macro step).
    if (t > last_fire_) heat_passed_ += last_q_ * (t - last_fire_);
    a_.ReadField(ta_, value_);
    const double ta = value_(0, 0);
    b_.ReadField(tb_, value_);
    const double q = conductance_ * (value_(0, 0) - ta);  // into a
    value_(0, 0) = q;
    a_.WriteField(qa_, value_);
    value_(0, 0) = -q;
    b_.WriteField(qb_, value_);
    last_fire_ = t;
    last_q_ = -q;  // from a to b
    return gipsi::StepStatus::Ok();
  }

 private:
  gipsi::SimObject& a_;
  gipsi::SimObject& b_;
  double conductance_;
  gipsi::FieldId ta_, tb_, qa_, qb_;
  Eigen::MatrixXd value_ = Eigen::MatrixXd::Zero(1, 1);
  double heat_passed_ = 0, last_fire_ = 0, last_q_ = 0;
};

void Register(gipsi::TypeRegistry& registry) {
  registry.objects.Register(
      "ThermalNode",
      [](const gipsi::ObjectBuildContext& ctx) -> std::unique_ptr<gipsi::SimObject> {
        ctx.CheckKeys({"capacity", "temperature"});
        auto integrator = ctx.params.Has("integrator")
                              ? ctx.registry.CreateIntegrator(ctx.params.At("integrator"))
                              : std::make_unique<gipsi::RungeKutta4>();
        return std::make_unique<ThermalNode>(ctx.name, ctx.params.Positive("capacity"),
                                             ctx.params.Positive("temperature"),
                                             std::move(integrator));
      },
      "(consumer) a lumped heat capacity");
  registry.connectors.Register(
      "Conductor",
      [](const gipsi::ConnectorBuildContext& ctx) -> std::unique_ptr<gipsi::Connector> {
        ctx.CheckKeys({"a", "b", "conductance"});
        return std::make_unique<Conductor>(ctx.name, ctx.Object("a"), ctx.Object("b"),
                                           ctx.params.Positive("conductance"));
      },
      "(consumer) a thermal conductance between two ThermalNodes");
}

}  // namespace thermal

namespace {

int failures = 0;

void Check(bool ok, const std::string& what) {
  std::printf("%s: %s\n", ok ? "ok  " : "FAIL", what.c_str());
  if (!ok) ++failures;
}

constexpr double kCa = 2.0, kCb = 3.0, kG = 0.5, kTa0 = 400, kTb0 = 300, kDt = 0.01;

nlohmann::json SceneJson() {
  nlohmann::json scene;
  scene["gipsi"] = 1;
  scene["units"] = "SI";
  scene["objects"]["hot"] = {{"type", "ThermalNode"},
                             {"capacity", kCa},
                             {"temperature", kTa0},
                             {"integrator", "RK4"},
                             {"dt", kDt}};
  scene["objects"]["cold"] = {
      {"type", "ThermalNode"}, {"capacity", kCb}, {"temperature", kTb0}, {"dt", kDt}};
  scene["connectors"]["bar"] = {
      {"type", "Conductor"}, {"a", "hot"}, {"b", "cold"}, {"conductance", kG}};
  scene["schedule"] = {{"end", 10.0}, {"dt", kDt}};
  return scene;
}

gipsi::Scene Load(const nlohmann::json& scene, gipsi::TypeRegistry& registry) {
  return gipsi::LoadSceneFromString(scene.dump(), "thermal.json", std::filesystem::current_path(),
                                    registry);
}

double Temperature(const gipsi::Kernel& kernel, const std::string& object) {
  const gipsi::SimObject& o = kernel.FindObject(object);
  Eigen::MatrixXd t(1, 1);
  o.ReadField(o.FindField("temperature"), t);
  return t(0, 0);
}

}  // namespace

/// Usage: thermal_consumer [DIR] (DIR, default the working folder, takes a checkpoint file).
int main(int argc, char** argv) {
  gipsi::TypeRegistry registry;
  gipsi::RegisterBuiltins(registry);
  thermal::Register(registry);

  // One run to the end, with a checkpoint half-way.
  gipsi::Scene scene = Load(SceneJson(), registry);
  gipsi::Kernel& kernel = *scene.kernel;
  const std::filesystem::path checkpoint =
      std::filesystem::path(argc > 1 ? argv[1] : ".") / "thermal.ckpt";
  Check(kernel.Run(5.0).ok(), "runs to 5 s");
  kernel.WriteCheckpoint(checkpoint);
  const gipsi::RunResult result = kernel.Run(10.0);
  Check(result.ok(), "runs to 10 s " + result.diagnostic);
  const double ta = Temperature(kernel, "hot"), tb = Temperature(kernel, "cold");

  const double energy0 = kCa * kTa0 + kCb * kTb0;
  const double energy = kCa * ta + kCb * tb;
  Check(std::abs(energy - energy0) <= 1e-12 * energy0,
        "energy conserved: " + std::to_string(energy) + " J vs " + std::to_string(energy0));

  const auto steps = static_cast<double>(kernel.macro_steps());
  const double factor = 1 - kG * kDt * (1 / kCa + 1 / kCb);
  const double expected_d = (kTa0 - kTb0) * std::pow(factor, steps);
  Check(std::abs((ta - tb) - expected_d) <= 1e-10 * (kTa0 - kTb0),
        "difference after " + std::to_string(kernel.macro_steps()) +
            " steps: " + std::to_string(ta - tb) + " K, expected " + std::to_string(expected_d));

  // The conductor's own count (a sum of 1000 flows times dt: rounding ~1e-13 relative).
  const auto& bar =
      dynamic_cast<const thermal::Conductor&>(scene.kernel->coordinator().connector(0));
  const double heat = bar.HeatPassedBy(kernel.time());
  Check(std::abs(heat - kCa * (kTa0 - ta)) <= 1e-10 * kCa * (kTa0 - kTb0),
        "heat counted by the conductor " + std::to_string(heat) + " J vs " +
            std::to_string(kCa * (kTa0 - ta)) + " J lost by the hot node");

  // Restore the half-way checkpoint into a freshly loaded scene and finish: bitwise the same.
  gipsi::Scene resumed = Load(SceneJson(), registry);
  resumed.kernel->ReadCheckpoint(checkpoint);
  std::filesystem::remove(checkpoint);
  Check(resumed.kernel->Run(10.0).ok(), "resumed run to 10 s");
  const auto& resumed_bar =
      dynamic_cast<const thermal::Conductor&>(resumed.kernel->coordinator().connector(0));
  Check(Temperature(*resumed.kernel, "hot") == ta && Temperature(*resumed.kernel, "cold") == tb &&
            resumed_bar.HeatPassedBy(resumed.kernel->time()) == heat,
        "resumed run ends bitwise equal (temperatures and the conductor's count)");

  // A bad value of the new type's parameter: refused with its JSON path.
  nlohmann::json bad = SceneJson();
  bad["objects"]["cold"]["capacity"] = -1;
  std::string message;
  try {
    Load(bad, registry);
  } catch (const gipsi::InputError& e) {
    message = e.what();
  }
  Check(message.find("objects.cold.capacity") != std::string::npos,
        "a negative capacity is refused at its path: " + message);

  std::printf("%s\n", failures == 0 ? "all checks passed" : "FAILED");
  return failures == 0 ? 0 : 1;
}
