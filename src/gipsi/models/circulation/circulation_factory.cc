/// @file
/// Scene-file factory of "Circulation" (keys documented in docs/scene-format.md and
/// docs/circulation.md), and the "closed_loop" preset with its parameters and their sources.

#include <cctype>
#include <map>
#include <set>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/units.h"
#include "gipsi/models/circulation/circulation.h"

namespace gipsi {
namespace {

// The default closed loop: left atrium → mitral → left ventricle → aortic valve → aorta
// (3-element Windkessel: R_c in the aortic valve branch, C, R_p) → systemic veins → venous
// return → left atrium. Sources and reasoning in docs/circulation.md ("Default parameters").
constexpr const char* kClosedLoopPreset = R"({
  "period": "0.8 s",
  "compartments": {
    "la": {"type": "chamber", "e_max": "0.25 mmHg/mL", "e_min": "0.15 mmHg/mL",
           "unstressed_volume": "4 mL",
           "activation": {"shape": "double_hill", "onset": "0.68 s", "tau1": "0.088 s",
                          "tau2": "0.144 s", "m1": 1.32, "m2": 13.1},
           "volume": "60 mL"},
    "lv": {"type": "chamber", "e_max": "2.75 mmHg/mL", "e_min": "0.08 mmHg/mL",
           "unstressed_volume": "10 mL",
           "activation": {"shape": "double_hill", "onset": "0 s", "tau1": "0.2152 s",
                          "tau2": "0.3616 s", "m1": 1.32, "m2": 27.4},
           "volume": "120 mL"},
    "aorta": {"type": "compliance", "compliance": "1.2 mL/mmHg", "pressure": "85 mmHg"},
    "veins": {"type": "compliance", "compliance": "50 mL/mmHg", "pressure": "10.25 mmHg"}
  },
  "connections": {
    "mitral": {"type": "valve", "from": "la", "to": "lv", "resistance": "0.005 mmHg*s/mL"},
    "aortic": {"type": "valve", "from": "lv", "to": "aorta", "resistance": "0.05 mmHg*s/mL",
               "inertance": "0.0005 mmHg*s^2/mL"},
    "peripheral": {"type": "resistor", "from": "aorta", "to": "veins",
                   "resistance": "1.0 mmHg*s/mL"},
    "venous_return": {"type": "resistor", "from": "veins", "to": "la",
                      "resistance": "0.02 mmHg*s/mL"}
  }
})";

constexpr const char* kPressure = "Pa";
constexpr const char* kVolume = "m^3";
constexpr const char* kElastance = "Pa/m^3";
constexpr const char* kCompliance = "m^3/Pa";
constexpr const char* kResistance = "Pa*s/m^3";
constexpr const char* kInertance = "Pa*s^2/m^3";
constexpr const char* kFlow = "m^3/s";
constexpr const char* kTime = "s";

void CheckName(const JsonNode& where, const std::string& name) {
  if (name.empty()) where.Fail("an empty name");
  for (char ch : name)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_'))
      where.Fail(
          fmt::format("name '{}' may only contain letters, digits and '_' (it becomes "
                      "part of field names such as '{}_pressure')",
                      name, name));
}

Activation ParseActivation(const JsonNode& node, double period) {
  node.CheckKeys(
      {"shape", "period", "onset", "tau1", "tau2", "m1", "m2", "contraction", "relaxation"});
  Activation a;
  if (auto shape = node.Find("shape"))
    a.shape = shape->AsChoice({"double_hill", "cosine"}) == "cosine"
                  ? Activation::Shape::kCosine
                  : Activation::Shape::kDoubleHill;
  a.period = node.Has("period") ? ReadPositiveQuantity(node.At("period"), kTime) : period;
  a.onset = node.Has("onset") ? ReadQuantity(node.At("onset"), kTime) : 0.0;
  a.tau1 = node.Has("tau1") ? ReadPositiveQuantity(node.At("tau1"), kTime) : 0.269 * a.period;
  a.tau2 = node.Has("tau2") ? ReadPositiveQuantity(node.At("tau2"), kTime) : 0.452 * a.period;
  a.m1 = node.Positive("m1", a.m1);
  a.m2 = node.Positive("m2", a.m2);
  a.contraction = node.Has("contraction") ? ReadPositiveQuantity(node.At("contraction"), kTime)
                                          : 0.375 * a.period;
  a.relaxation = node.Has("relaxation") ? ReadPositiveQuantity(node.At("relaxation"), kTime)
                                        : 0.1875 * a.period;
  if (a.shape == Activation::Shape::kCosine && a.contraction + a.relaxation > a.period)
    node.Fail(fmt::format("contraction + relaxation = {} s exceeds the period {} s",
                          a.contraction + a.relaxation, a.period));
  a.Normalise();
  return a;
}

CompartmentSpec ParseCompartment(const std::string& name, const JsonNode& node, double period) {
  CheckName(node, name);
  CompartmentSpec s;
  s.name = name;
  const std::string type = node.At("type").AsChoice({"chamber", "compliance", "reservoir"});
  using K = CompartmentSpec::Kind;
  auto initial = [&](auto pressure_to_volume) {
    const bool has_v = node.Has("volume"), has_p = node.Has("pressure");
    if (has_v == has_p)
      node.Fail(
          "give the initial state as exactly one of \"volume\" (e.g. \"120 mL\") or "
          "\"pressure\" (e.g. \"8 mmHg\")");
    return has_v ? ReadPositiveQuantity(node.At("volume"), kVolume, true)
                 : pressure_to_volume(ReadQuantity(node.At("pressure"), kPressure));
  };
  if (type == "reservoir") {
    node.CheckKeys({"type", "pressure", "description"});
    s.kind = K::kReservoir;
    s.reservoir_pressure = ReadQuantity(node.At("pressure"), kPressure);
    return s;
  }
  s.unstressed_volume = node.Has("unstressed_volume")
                            ? ReadPositiveQuantity(node.At("unstressed_volume"), kVolume, true)
                            : 0.0;
  if (type == "compliance") {
    node.CheckKeys(
        {"type", "compliance", "unstressed_volume", "volume", "pressure", "description"});
    s.kind = K::kCompliance;
    s.compliance = ReadPositiveQuantity(node.At("compliance"), kCompliance);
    s.initial_volume = initial([&](double p) { return s.unstressed_volume + s.compliance * p; });
    return s;
  }
  node.CheckKeys({"type", "e_max", "e_min", "unstressed_volume", "activation", "volume", "pressure",
                  "driven_by", "coupling_compliance", "description"});
  s.kind = K::kChamber;
  const std::string drive = node.Has("driven_by")
                                ? node.At("driven_by").AsChoice({"elastance", "volume", "pressure"})
                                : "elastance";
  if (drive == "volume") {
    s.drive = CompartmentSpec::Drive::kVolume;
    s.compliance = node.Has("coupling_compliance")
                       ? ReadPositiveQuantity(node.At("coupling_compliance"), kCompliance)
                       : 0.01e-6 / 133.322387415;  // 0.01 mL/mmHg
    if (!node.Has("volume"))
      node.Fail("a chamber driven by volume needs its initial cavity \"volume\" (e.g. \"120 mL\")");
    s.initial_cavity_volume = ReadPositiveQuantity(node.At("volume"), kVolume, true);
    const double p0 = node.Has("pressure") ? ReadQuantity(node.At("pressure"), kPressure) : 0.0;
    s.initial_volume = s.initial_cavity_volume + s.compliance * p0;
    return s;
  }
  if (drive == "pressure") {
    s.drive = CompartmentSpec::Drive::kPressure;
    if (!node.Has("volume"))
      node.Fail("a chamber driven by pressure needs its initial \"volume\" (e.g. \"120 mL\")");
    s.initial_volume = ReadPositiveQuantity(node.At("volume"), kVolume, true);
    s.initial_pressure = node.Has("pressure") ? ReadQuantity(node.At("pressure"), kPressure) : 0.0;
    return s;
  }
  s.e_max = ReadPositiveQuantity(node.At("e_max"), kElastance);
  s.e_min = ReadPositiveQuantity(node.At("e_min"), kElastance);
  if (s.e_max < s.e_min)
    node.At("e_max").Fail(
        fmt::format("e_max ({} Pa/m^3) is below e_min ({} Pa/m^3)", s.e_max, s.e_min));
  s.activation =
      node.Has("activation")
          ? ParseActivation(node.At("activation"), period)
          : ParseActivation(JsonNode(nlohmann::ordered_json::object(), node.file(), node.path()),
                            period);
  const double e0 = s.e_min + (s.e_max - s.e_min) * s.activation.Evaluate(0);
  s.initial_volume = initial([&](double p) { return s.unstressed_volume + p / e0; });
  return s;
}

FlowWaveform ParseWaveform(const JsonNode& node) {
  FlowWaveform w;
  if (node.is_number() || node.is_string()) {
    w.mean = ReadQuantity(node, kFlow);
    return w;
  }
  const std::string kind = node.At("waveform").AsChoice({"constant", "sine", "half_sine", "field"});
  if (kind == "constant") {
    node.CheckKeys({"waveform", "value"});
    w.mean = ReadQuantity(node.At("value"), kFlow);
  } else if (kind == "sine") {
    node.CheckKeys({"waveform", "mean", "amplitude", "period"});
    w.kind = FlowWaveform::Kind::kSine;
    w.mean = node.Has("mean") ? ReadQuantity(node.At("mean"), kFlow) : 0.0;
    w.amplitude = ReadQuantity(node.At("amplitude"), kFlow);
    w.period = ReadPositiveQuantity(node.At("period"), kTime);
  } else if (kind == "half_sine") {
    node.CheckKeys({"waveform", "peak", "duration", "period"});
    w.kind = FlowWaveform::Kind::kHalfSine;
    w.amplitude = ReadQuantity(node.At("peak"), kFlow);
    w.period = ReadPositiveQuantity(node.At("period"), kTime);
    w.duration = ReadPositiveQuantity(node.At("duration"), kTime);
    if (w.duration > w.period) node.At("duration").Fail("the pulse is longer than its period");
  } else {
    node.CheckKeys({"waveform"});
    w.kind = FlowWaveform::Kind::kField;
  }
  return w;
}

ConnectionSpec ParseConnection(const std::string& name, const JsonNode& node,
                               const std::map<std::string, int, std::less<>>& compartments) {
  CheckName(node, name);
  ConnectionSpec s;
  s.name = name;
  const std::string type = node.At("type").AsChoice({"resistor", "valve", "source"});
  auto compartment = [&](std::string_view key) {
    const JsonNode where = node.At(key);
    const std::string target = where.AsString();
    const auto it = compartments.find(target);
    if (it == compartments.end()) {
      std::vector<std::string> names;
      std::string list;
      for (const auto& [n, i] : compartments) {
        names.push_back(n);
        list += (list.empty() ? "" : ", ") + n;
      }
      where.Fail(fmt::format("unknown compartment '{}'{}; the compartments are: {}", target,
                             SuggestClosest(target, names), list));
    }
    return it->second;
  };
  s.to = compartment("to");
  if (node.Has("resistance"))
    s.resistance = ReadPositiveQuantity(node.At("resistance"), kResistance, true);
  if (type == "source") {
    node.CheckKeys({"type", "to", "flow", "resistance", "description"});
    s.kind = ConnectionSpec::Kind::kSource;
    s.source = ParseWaveform(node.At("flow"));
    return s;
  }
  node.CheckKeys({"type", "from", "to", "resistance", "inertance", "flow", "description"});
  s.kind = type == "valve" ? ConnectionSpec::Kind::kValve : ConnectionSpec::Kind::kResistor;
  s.from = compartment("from");
  if (s.from == s.to) node.At("to").Fail("a connection must join two different compartments");
  if (node.Has("inertance"))
    s.inertance = ReadPositiveQuantity(node.At("inertance"), kInertance, true);
  if (!(s.resistance > 0) && !(s.inertance > 0))
    node.Fail(
        "give a positive \"resistance\" (or an \"inertance\"): a connection without "
        "either has no defined flow");
  if (node.Has("flow")) {
    if (!(s.inertance > 0))
      node.At("flow").Fail("an initial flow is a state only of connections with an inertance");
    s.initial_flow = ReadQuantity(node.At("flow"), kFlow);
  }
  return s;
}

CirculationParams ParseCirculation(const JsonNode& p) {
  CirculationParams params;
  const double period = p.Has("period") ? ReadPositiveQuantity(p.At("period"), kTime) : 0.8;
  std::map<std::string, int, std::less<>> index;
  const JsonNode compartments = p.At("compartments");
  if (compartments.size() == 0) compartments.Fail("a circulation needs at least one compartment");
  for (const auto& [name, node] : compartments.Members()) {
    index[name] = static_cast<int>(params.compartments.size());
    params.compartments.push_back(ParseCompartment(name, node, period));
  }
  if (auto connections = p.Find("connections")) {
    for (const auto& [name, node] : connections->Members()) {
      if (index.count(name) > 0)
        node.Fail(fmt::format("'{}' names both a compartment and a connection", name));
      params.connections.push_back(ParseConnection(name, node, index));
    }
  }
  if (auto tol = p.Find("tolerance")) {
    tol->CheckKeys({"relative", "absolute"});
    params.relative_tolerance = tol->Positive("relative", params.relative_tolerance);
    if (tol->Has("absolute"))
      params.absolute_tolerance = ReadPositiveQuantity(tol->At("absolute"), kVolume);
  }
  if (p.Has("max_step")) params.max_step = ReadPositiveQuantity(p.At("max_step"), kTime);
  if (p.Has("event_tolerance"))
    params.event_tolerance = ReadPositiveQuantity(p.At("event_tolerance"), kTime);
  params.log_events = p.Bool("log_events", params.log_events);
  if (auto cap = p.Find("event_log_capacity")) {
    const std::int64_t n = cap->AsInt();
    if (n < 1 || n > 100'000'000) cap->Expected("an integer in [1, 100000000]");
    params.event_log_capacity = static_cast<std::size_t>(n);
  }
  return params;
}

}  // namespace

void RegisterCirculation(TypeRegistry& registry) {
  registry.objects.Register(
      "Circulation",
      [](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        ctx.CheckKeys({"preset", "period", "compartments", "connections", "tolerance", "max_step",
                       "event_tolerance", "log_events", "event_log_capacity"});
        const JsonNode& p = ctx.params;
        if (!p.Has("preset")) return std::make_unique<Circulation>(ctx.name, ParseCirculation(p));
        // A preset is a document the scene's keys patch (RFC 7386 merge patch): a scene may
        // change one parameter ("compartments": {"lv": {"e_max": "3 mmHg/mL"}}), add
        // compartments and connections, or remove one with null.
        (void)p.At("preset").AsChoice({"closed_loop"});
        auto merged = nlohmann::ordered_json::parse(kClosedLoopPreset);
        nlohmann::ordered_json patch = p.raw();
        patch.erase("preset");
        merged.merge_patch(patch);
        const JsonNode root(merged,
                            fmt::format("{} (preset closed_loop patched by the scene)", p.file()),
                            p.path());
        return std::make_unique<Circulation>(ctx.name, ParseCirculation(root));
      },
      "lumped (0D) circulation: time-varying elastance chambers, compliances, resistances, "
      "inertances and valves as hybrid systems (adaptive Dormand-Prince with event location)");
}

}  // namespace gipsi
