#include "gipsi/haptics/haptic_probe.h"

#include <sched.h>

#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"
#include "gipsi/core/local_model.h"
#include "gipsi/haptics/igtl_surface_sender.h"

namespace gipsi {

/// Ticks the probe on the haptic thread and hands its outputs to the probe's step.
class HapticProbe::LoopRenderer final : public HapticRenderer {
 public:
  explicit LoopRenderer(HapticProbe& probe) : probe_(probe) {}
  Vec3 Run(double t, double dt) noexcept override {
    const double th = probe_.loop_origin_ + t;  // the haptic clock in simulation seconds
    Sample& s = probe_.samples_->back();
    if (probe_.tick_) {
      s.force = probe_.tick_->Run(th, dt);
      s.position = probe_.tick_->tool_position();
      s.proxy = probe_.tick_->proxy();
      s.model_force = probe_.tick_->model_force();
    } else {  // not coupled: the device moves freely
      s.position = s.proxy = probe_.spec_.workspace.ToSimulation(probe_.device_->Read(th).position);
    }
    s.ticks = ++ticks_;
    probe_.samples_->Publish();
    return s.force;
  }

 private:
  HapticProbe& probe_;
  std::int64_t ticks_ = 0;
};

HapticProbe::HapticProbe(std::string name, const HapticProbeSpec& spec)
    : SimObject(std::move(name)), spec_(spec) {
  if (spec.igtl) {
    auto igtl = std::make_unique<IgtlDevice>(*spec.igtl);
    igtl_ = igtl.get();
    device_ = std::move(igtl);
  } else if (spec.mouse) {
    auto mouse = std::make_unique<MouseDevice>(*spec.mouse);
    mouse_ = mouse.get();
    device_ = std::move(mouse);
  } else {
    auto scripted = std::make_unique<VirtualDevice>(spec.path);
    virtual_ = scripted.get();
    device_ = std::move(scripted);
  }
  if (!(spec.rate > 0 && spec.rate <= 10000))
    throw InputError(
        fmt::format("haptic probe '{}': rate {} Hz outside (0, 10000]", this->path(), spec.rate));
  using L = FieldLocation;
  using A = FieldAccess;
  f_force_ = DeclareField({"tool_force", L::kGlobal, 3, "N", A::kRead,
                           "force commanded to the device (after the safety stage)"});
  f_position_ = DeclareField({"tool_position", L::kGlobal, 3, "m", A::kRead, "device position"});
  f_proxy_ = DeclareField({"proxy_position", L::kGlobal, 3, "m", A::kRead,
                           "god-object: the device held on the local surface"});
  f_model_force_ = DeclareField(
      {"model_force", L::kGlobal, 1, "N", A::kRead, "normal contact force of the local model"});
  position_ = proxy_ = initial_ = spec_.workspace.ToSimulation(device_->Read(0).position);
  if (spec_.realtime) {
    Sample first;
    first.position = first.proxy = initial_;
    samples_ = std::make_unique<LatestValue<Sample>>(first);
    renderer_ = std::make_unique<LoopRenderer>(*this);
    loop_ =
        std::make_unique<HapticLoop>(*renderer_, spec_.rate, std::size_t{1} << 20, *spec_.realtime);
  }
  BindGatheredState<HapticProbeState>([this](HapticProbeState& s) { GetState(s); },
                                      [this](const HapticProbeState& s) { SetState(s); });
}

HapticProbe::~HapticProbe() { StopLoop(); }

void HapticProbe::StartLoop(double sim_time) {
  GIPSI_CHECK(loop_ != nullptr, "HapticProbe '{}' is not real-time", path());
  GIPSI_CHECK(!loop_->running(), "HapticProbe '{}': loop started twice", path());
  loop_origin_ = sim_time;  // before the thread starts: it reads it
  loop_->Start();
}

HapticLoopStats HapticProbe::StopLoop() {
  if (!loop_) return {};
  loop_->Stop();
  return loop_->Stats();
}

HapticRenderer* HapticProbe::loop_renderer() { return renderer_.get(); }

double HapticProbe::HapticTime(double sim_time) const {
  if (!loop_running()) return sim_time;
  return loop_origin_ + loop_->Elapsed();
}

void HapticProbe::Attach(LatestValue<LocalDynamicModel>& models,
                         LatestValue<HapticFeedback>& feedback) {
  if (tick_) throw InputError(fmt::format("haptic probe '{}' is coupled to two objects", path()));
  tick_ =
      std::make_unique<LocalModelTick>(*device_, spec_.workspace, models, &feedback, spec_.tick);
}

StepStatus HapticProbe::StepRealtime() {
  if (!loop_running())
    return StepStatus::Failed(
        "the probe is real-time (\"realtime\") but its haptic loop is not running: run the scene "
        "with gipsi run or gipsi view (a program starts the loop with RealtimeHaptics)");
  // Never ahead of the wall clock (the device, the models' age and the watchdog live on it):
  // the coordinator waited for it before this step (WallClockPaced).
  if (samples_->Fetch()) {
    const Sample& s = samples_->front();
    force_ = s.force;
    position_ = s.position;
    proxy_ = s.proxy;
    model_force_ = s.model_force;
    ticks_ = s.ticks;
  }
  return StepStatus::Ok();
}

StepStatus HapticProbe::DoStep(double t, double dt) {
  if (loop_) return StepRealtime();
  const int n = std::max(1, static_cast<int>(std::lround(dt * spec_.rate)));
  const double h = dt / n;
  for (int k = 1; k <= n; ++k) {
    const double tk = t + k * h;
    if (tick_) {
      force_ = tick_->Run(tk, h);
      proxy_ = tick_->proxy();
      model_force_ = tick_->model_force();
      position_ = tick_->tool_position();
    } else {
      position_ = proxy_ = spec_.workspace.ToSimulation(device_->Read(tk).position);
    }
    ++ticks_;
  }
  return StepStatus::Ok();
}

void HapticProbe::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  if (id == f_force_) {
    out.col(0) = force_;
  } else if (id == f_position_) {
    out.col(0) = position_;
  } else if (id == f_proxy_) {
    out.col(0) = proxy_;
  } else if (id == f_model_force_) {
    out(0, 0) = model_force_;
  }
}

void HapticProbe::DoWriteField(FieldId /*id*/, const Eigen::Ref<const Eigen::MatrixXd>& /*in*/) {
  GIPSI_CHECK(false, "HapticProbe has no writable field");
}

// ---------------------------------------------------------------------------------------------

HapticCoupling::HapticCoupling(std::string name, std::unique_ptr<LocalModelBuilder> builder,
                               SimObject& device, HapticBridgeParams params)
    : Connector(std::move(name)),
      device_(device),
      endpoint_(HapticEndpointOf(device)),
      builder_(std::move(builder)) {
  GIPSI_CHECK(builder_ != nullptr);
  const SimObject& object = builder_->object();
  if (object.boundary().num_vertices() == 0)
    throw InputError(fmt::format("object '{}' has no boundary surface", object.path()));
  UseCapability("object", object, "haptic local model");
  UseBoundaryConditions("object", object);
  UseCapability("device", device_, "haptic device");
  params.period = 1.0 / endpoint_.haptic_rate();
  bridge_ = std::make_unique<HapticBridge>(*builder_, params);
  BindGatheredState<HapticBridgeState>(
      [this](HapticBridgeState& s) { bridge_->GetState(s); },
      [this](const HapticBridgeState& s) { bridge_->SetState(s); });
  bridge_->SeedTool(endpoint_.initial_position());
  endpoint_.Attach(bridge_->models(), bridge_->feedback());
  // A first model at the object's initial state, so a real-time loop started before the first
  // step (the viewer, paused) already renders the contact. The first firing supersedes it
  // before any synchronous tick could fetch it.
  bridge_->Publish(device_.time());
}

HapticCoupling::~HapticCoupling() { endpoint_.StopLoop(); }

StepStatus HapticCoupling::DoFire(double t) {
  bridge_->ApplyFeedback();
  bridge_->Publish(endpoint_.HapticTime(t));
  return StepStatus::Ok();
}

// ---------------------------------------------------------------------------------------------

namespace {

MouseDeviceParams ParseMouseDevice(const JsonNode& node) {
  node.CheckKeys({"type", "start", "wheel_step"});
  MouseDeviceParams params;
  params.start = node.Vector3("start");
  params.wheel_step = node.Positive("wheel_step", params.wheel_step);
  return params;
}

std::optional<HapticRealtime> ParseRealtime(const JsonNode& node) {
  const char* const expected =
      "true, false or an object {\"fifo\": false, \"priority\": 80, \"cpu\": -1, \"spin\": 0}";
  if (node.is_object()) {
    node.CheckKeys({"fifo", "priority", "cpu", "spin"});
    HapticRealtime realtime;
    realtime.fifo = node.Bool("fifo", realtime.fifo);
    const std::int64_t priority = node.Int("priority", realtime.priority);
    if (priority < 1 || priority > 99) node.At("priority").Expected("an integer in 1-99");
    realtime.priority = static_cast<int>(priority);
    const std::int64_t cpu = node.Int("cpu", realtime.cpu);
    if (cpu < -1 || cpu >= CPU_SETSIZE)
      node.At("cpu").Expected(
          fmt::format("a CPU number in 0-{}, or -1 (no pinning)", CPU_SETSIZE - 1));
    realtime.cpu = static_cast<int>(cpu);
    realtime.spin = node.NonNegative("spin", realtime.spin);  // checked against the rate later
    return realtime;
  }
  if (node.raw().is_boolean())
    return node.AsBool() ? std::optional<HapticRealtime>(HapticRealtime{}) : std::nullopt;
  node.Expected(expected);
}

}  // namespace

void RegisterHaptics(TypeRegistry& registry) {
  registry.objects.Register(
      "HapticProbe",
      [](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        const JsonNode& p = ctx.params;
        ctx.CheckKeys({"path", "device", "rate", "coupling_stiffness", "coupling_damping",
                       "blend_time", "max_force", "max_rate", "stale_after", "fade_time",
                       "workspace_scale", "workspace_offset", "realtime"});
        HapticProbeSpec spec;
        if (p.Has("device") == p.Has("path"))
          p.Fail(
              "a HapticProbe needs exactly one of \"path\" (a virtual device) and \"device\" (an "
              "OpenIGTLink or Mouse device)");
        if (p.Has("device")) {
          const JsonNode device = p.At("device");
          if (device.is_object() && device.Has("type") && device.At("type").is_string() &&
              device.At("type").AsString() == "Mouse") {
            spec.mouse = ParseMouseDevice(device);
            for (const char* key : {"workspace_scale", "workspace_offset"})
              if (p.Has(key))
                p.At(key).Fail("a Mouse device works in scene coordinates: no workspace mapping");
          } else {
            spec.igtl = ParseIgtlDevice(device);
          }
        } else {
          const JsonNode path = p.At("path");
          if (!path.is_array() || path.size() == 0)
            path.Expected("an array of [t, x, y, z] keyframes");
          for (const JsonNode& key : path.Items()) {
            const std::vector<double> k = key.AsNumbers();
            if (k.size() != 4) key.Expected("[t, x, y, z]");
            if (!spec.path.empty() && !(k[0] > spec.path.back().time))
              key.Fail("keyframe times must increase strictly");
            spec.path.push_back({k[0], Vec3(k[1], k[2], k[3]), 0});
          }
        }
        spec.workspace.scale = p.Positive("workspace_scale", 1.0);
        spec.workspace.offset = p.Vector3("workspace_offset", Vec3::Zero());
        spec.rate = p.Positive("rate", 1000.0);
        if (spec.rate > 10000) p.At("rate").Expected("a rate in (0, 10000] Hz");
        spec.tick.coupling.stiffness = p.Positive("coupling_stiffness", 5000.0);
        spec.tick.coupling.damping = p.NonNegative("coupling_damping", 0.0);
        spec.tick.blend_time = p.NonNegative("blend_time", spec.tick.blend_time);
        spec.tick.safety.max_force = p.Positive("max_force", spec.tick.safety.max_force);
        spec.tick.safety.max_rate = p.Positive("max_rate", spec.tick.safety.max_rate);
        spec.tick.safety.stale_after = p.Positive("stale_after", spec.tick.safety.stale_after);
        spec.tick.safety.fade_time = p.NonNegative("fade_time", spec.tick.safety.fade_time);
        if (p.Has("realtime")) spec.realtime = ParseRealtime(p.At("realtime"));
        if (spec.realtime && !(spec.realtime->spin < 1 / spec.rate))
          p.At("realtime")
              .At("spin")
              .Expected(
                  fmt::format("a time in [0, {}) s, less than the haptic period", 1 / spec.rate));
        if (!spec.igtl) return std::make_unique<HapticProbe>(ctx.name, spec);
        try {
          return std::make_unique<HapticProbe>(ctx.name, spec);
        } catch (const InputError& e) {
          p.At("device").Fail(e.what());
        }
      },
      "haptic device (virtual on a scripted path, or OpenIGTLink) rendering local models at its "
      "rate");
  registry.connectors.Register(
      "HapticCoupling",
      [](const ConnectorBuildContext& ctx) -> std::unique_ptr<Connector> {
        const JsonNode& p = ctx.params;
        ctx.CheckKeys({"object", "device", "capture_distance", "rings"});
        SimObject& object = ctx.Object("object");
        SimObject& device = ctx.Object("device");
        try {
          (void)HapticEndpointOf(device);
        } catch (const InputError& e) {
          p.At("device").Fail(e.what());
        }
        HapticBridgeParams params;
        params.capture_distance = p.NonNegative("capture_distance", params.capture_distance);
        const std::int64_t rings = p.Int("rings", 1);
        if (rings < 0 || rings > 5) p.At("rings").Expected("an integer in [0, 5]");
        const std::string type(object.type_name());
        if (!LocalModels(ctx.registry).Contains(type))
          p.At("object").Fail(fmt::format(
              "object '{}' is a {}, which has no haptic local model (types with one: {})",
              object.path(), type, fmt::join(LocalModels(ctx.registry).Names(), ", ")));
        try {
          return std::make_unique<HapticCoupling>(
              ctx.name,
              LocalModels(ctx.registry).Get(type, p.At("object"))(object, static_cast<int>(rings)),
              device, params);
        } catch (const InputError& e) {
          p.Fail(e.what());
        }
      },
      "multi-rate haptics: local models of an object rendered by a HapticProbe");
  registry.connectors.Register(
      "OpenIGTLinkSurface",
      [](const ConnectorBuildContext& ctx) -> std::unique_ptr<Connector> {
        const JsonNode& p = ctx.params;
        ctx.CheckKeys({"object", "device", "rate", "name"});
        const SimObject& object = ctx.Object("object");
        auto* endpoint = dynamic_cast<HapticEndpoint*>(&ctx.Object("device"));
        if (endpoint == nullptr || endpoint->igtl_device() == nullptr)
          p.At("device").Expected("the name of a HapticProbe with an OpenIGTLink device");
        const double rate = p.Positive("rate", 30.0);
        const std::string name = p.String("name", object.name());
        if (name.empty()) p.At("name").Expected("a non-empty POLYDATA device name");
        try {
          return std::make_unique<IgtlSurfaceSender>(ctx.name, object, *endpoint->igtl_device(),
                                                     rate, name);
        } catch (const InputError& e) {
          p.Fail(e.what());
        }
      },
      "sends an object's deformed boundary surface as OpenIGTLink POLYDATA (e.g. to 3D Slicer)");
}

}  // namespace gipsi
