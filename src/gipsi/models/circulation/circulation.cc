#include "gipsi/models/circulation/circulation.h"

#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"

namespace gipsi {
namespace {

AdaptiveOdeOptions OdeOptions(const CirculationParams& p, const Circuit& circuit) {
  AdaptiveOdeOptions options;
  options.relative_tolerance = p.relative_tolerance;
  options.absolute_tolerances = VecX::Constant(circuit.ode_size(), p.absolute_tolerance);
  options.max_step = p.max_step;
  options.event_tolerance = p.event_tolerance;
  return options;
}

}  // namespace

Circulation::Circulation(std::string name, CirculationParams params)
    : SimObject(std::move(name)),
      params_(std::move(params)),
      circuit_(params_.compartments, params_.connections, state_.circuit) {
  using L = FieldLocation;
  using A = FieldAccess;
  state_.x = circuit_.InitialState();
  circuit_.InitialiseValves(0, state_.x);
  ode_.Prepare(circuit_.ode_size(), static_cast<int>(circuit_.valves().size()),
               OdeOptions(params_, circuit_));
  state_.ode = ode_.NewState();
  trial_ode_ = ode_.NewState();
  state_.pressure.setZero(circuit_.num_compartments());
  state_.flow.setZero(circuit_.num_connections());
  state_.events = Stamped<ValveEventLog>(ValveEventLog(params_.event_log_capacity));
  BindState(state_);

  for (int c = 0; c < circuit_.num_compartments(); ++c) {
    const auto& s = circuit_.compartments()[static_cast<std::size_t>(c)];
    Declare({s.name + "_pressure", L::kGlobal, 1, "Pa", A::kRead, "compartment pressure"},
            Quantity::kPressure, c);
    Declare({s.name + "_volume", L::kGlobal, 1, "m3", A::kRead, "compartment blood volume"},
            Quantity::kVolume, c);
    if (s.kind != CompartmentSpec::Kind::kChamber) continue;
    if (s.drive == CompartmentSpec::Drive::kElastance) {
      Declare({s.name + "_elastance", L::kGlobal, 1, "Pa/m3", A::kRead, "chamber elastance E(t)"},
              Quantity::kElastance, c);
    } else if (s.drive == CompartmentSpec::Drive::kPressure) {
      Declare({s.name + "_pressure_input", L::kGlobal, 1, "Pa", A::kReadWrite,
               "prescribed chamber pressure (input; held until written again)"},
              Quantity::kPressureInput, c);
    } else {
      Declare({s.name + "_cavity_volume", L::kGlobal, 1, "m3", A::kReadWrite,
               "volume of the driving 3-D cavity (input)"},
              Quantity::kCavityVolume, c);
      Declare({s.name + "_cavity_volume_rate", L::kGlobal, 1, "m3/s", A::kReadWrite,
               "rate of the driving cavity volume (input; extrapolates it over a step)"},
              Quantity::kCavityRate, c);
    }
  }
  for (int c = 0; c < circuit_.num_connections(); ++c) {
    const auto& s = circuit_.connections()[static_cast<std::size_t>(c)];
    const bool field_source =
        s.kind == ConnectionSpec::Kind::kSource && s.source.kind == FlowWaveform::Kind::kField;
    Declare({s.name + "_flow", L::kGlobal, 1, "m3/s", field_source ? A::kReadWrite : A::kRead,
             field_source ? "prescribed flow (input)" : "flow from 'from' to 'to'"},
            Quantity::kFlow, c);
    Declare({s.name + "_pressure_drop", L::kGlobal, 1, "Pa", A::kRead,
             "p_from - p_to (a source: R q, the pressure it works against above 'to')"},
            Quantity::kPressureDrop, c);
    if (s.kind != ConnectionSpec::Kind::kSource)
      Declare({s.name + "_resistance", L::kGlobal, 1, "Pa*s/m3", A::kReadWrite,
               "resistance R (input: the scene's value until written; > 0, or >= 0 with an "
               "inertance)"},
              Quantity::kResistance, c);
  }
  for (std::size_t k = 0; k < circuit_.valves().size(); ++k)
    Declare({valve_name(static_cast<int>(k)) + "_open", L::kGlobal, 1, "1", A::kRead,
             "valve state: 1 open, 0 closed"},
            Quantity::kValveOpen, static_cast<int>(k));
  Declare({"total_volume", L::kGlobal, 1, "m3", A::kRead, "sum of all compartment volumes"},
          Quantity::kTotalVolume, -1);
  Declare({"valve_events", L::kGlobal, 1, "1", A::kRead, "valve transitions so far"},
          Quantity::kValveEvents, -1);
  Declare({"adaptive_steps", L::kGlobal, 1, "1", A::kRead, "accepted adaptive steps so far"},
          Quantity::kSteps, -1);
  UpdateOutputs(0);
}

void Circulation::Declare(FieldInfo info, Quantity quantity, int index) {
  if (TryFindField(info.name))
    throw InputError(fmt::format(
        "object '{}': the field name '{}' arises twice from the compartment and connection "
        "names; rename one of them",
        path(), info.name));
  const FieldId id = DeclareField(std::move(info));
  GIPSI_CHECK(id.value() == static_cast<std::int64_t>(targets_.size()));
  targets_.push_back({quantity, index});
}

int Circulation::FindCompartment(std::string_view name) const {
  for (int c = 0; c < circuit_.num_compartments(); ++c)
    if (circuit_.compartments()[static_cast<std::size_t>(c)].name == name) return c;
  return -1;
}

int Circulation::FindPressureDrivenChamber(std::string_view name) const {
  std::vector<std::string> driven;
  for (const CompartmentSpec& spec : circuit_.compartments())
    if (spec.kind == CompartmentSpec::Kind::kChamber &&
        spec.drive == CompartmentSpec::Drive::kPressure)
      driven.push_back(spec.name);
  const int c = FindCompartment(name);
  const std::string those =
      driven.empty() ? std::string("it has none; give a chamber \"driven_by\": \"pressure\"")
                     : fmt::format("those that are: {}", fmt::join(driven, ", "));
  if (c < 0)
    throw InputError(
        fmt::format("object '{}' has no compartment '{}' ({})", this->path(), name, those));
  const CompartmentSpec& spec = circuit_.compartments()[static_cast<std::size_t>(c)];
  if (spec.kind != CompartmentSpec::Kind::kChamber ||
      spec.drive != CompartmentSpec::Drive::kPressure)
    throw InputError(fmt::format(
        "compartment '{}' of '{}' must be a chamber with \"driven_by\": \"pressure\" (the wall "
        "solves its pressure; {})",
        name, this->path(), those));
  return c;
}

int Circulation::FindConnection(std::string_view name) const {
  for (int c = 0; c < circuit_.num_connections(); ++c)
    if (circuit_.connections()[static_cast<std::size_t>(c)].name == name) return c;
  return -1;
}

const std::string& Circulation::valve_name(int k) const {
  return circuit_
      .connections()[static_cast<std::size_t>(circuit_.valves()[static_cast<std::size_t>(k)])]
      .name;
}

double Circulation::total_volume() const {
  return state_.x.head(circuit_.num_compartments()).sum();
}

void Circulation::UpdateOutputs(double t) {
  circuit_.CalcPressures(t, state_.x, state_.pressure);
  circuit_.CalcFlows(t, state_.x, state_.pressure, state_.flow);
}

StepStatus Circulation::Integrate(AdaptiveOdeState& memory, double t, double dt, VecX& x,
                                  bool record) {
  const double t_end = t + dt;
  double now = t;
  const OdeView view(circuit_);
  int switches = 0;
  auto log_switch = [&](int k) {
    circuit_.SwitchValve(k, x);
    if (record) state_.events.Write().Record({now, k, circuit_.valve_state(k)});
    return ++switches <= params_.max_events_per_step;
  };
  while (true) {
    // Transitions pending at the current point (after an external input changed a pressure,
    // or two valves switching at the same instant).
    for (int k; (k = ode_.FirstPositive(circuit_.guards(), now, x)) >= 0;)
      if (!log_switch(k))
        return StepStatus::Failed("valves switch without end within one step (chattering)", k, now);
    const AdaptiveOdeResult result =
        ode_.Integrate(memory, view, now, t_end, x, &circuit_.guards());
    if (record) {
      state_.accepted += result.accepted;
      state_.rejected += result.rejected;
      state_.evaluations += result.evaluations;
    }
    using Outcome = AdaptiveOdeResult::Outcome;
    if (result.outcome == Outcome::kEvent) {
      if (!log_switch(result.event))
        return StepStatus::Failed("valves switch without end within one step (chattering)",
                                  result.event, now);
      continue;
    }
    if (result.outcome == Outcome::kReachedEnd) return StepStatus::Ok();
    if (record) UpdateOutputs(now);
    if (result.outcome == Outcome::kNonFinite)
      return StepStatus::Diverged("circulation state became non-finite (at this time)", -1, now);
    if (result.outcome == Outcome::kStepTooSmall)
      return StepStatus::Failed(
          "adaptive step fell below its minimum at this time (stiff or singular circuit)", -1, now);
    return StepStatus::Failed("too many adaptive steps in one object step", -1, now);
  }
}

bool Circulation::PredictChamberVolume(int c, double dt, double p, double& volume) {
  GIPSI_CHECK(c >= 0 && c < circuit_.num_compartments() &&
              circuit_.compartments()[static_cast<std::size_t>(c)].drive ==
                  CompartmentSpec::Drive::kPressure);
  trial_x_ = state_.x;
  trial_valves_ = circuit_.valve_states();
  const double saved_pressure = circuit_.ChamberPressure(c);
  circuit_.SetChamberPressure(c, p);
  trial_ode_.next_step = state_.ode.next_step;
  const StepStatus status = Integrate(trial_ode_, time(), dt, trial_x_, false);
  circuit_.SetValveStates(trial_valves_);
  circuit_.SetChamberPressure(c, saved_pressure);
  volume = trial_x_[c];
  return status.ok() && std::isfinite(volume);
}

void Circulation::SetVolume(int c, double volume) {
  GIPSI_CHECK(c >= 0 && c < circuit_.num_compartments());
  state_.x[c] = volume;
  circuit_.InitialiseValves(time(), state_.x);
  UpdateOutputs(time());
}

StepStatus Circulation::DoStep(double t, double dt) {
  failed_compartment_ = failed_connection_ = -1;
  if (const int c = circuit_.ResistanceProblem(); c >= 0) {
    failed_connection_ = c;
    return StepStatus::Failed(
        "a written resistance is not usable (it must be finite and > 0, or >= 0 with an "
        "inertance)",
        c, circuit_.resistance(c));
  }
  const double t_end = t + dt;
  if (StepStatus status = Integrate(state_.ode, t, dt, state_.x, true); !status.ok()) return status;
  UpdateOutputs(t_end);
  for (Index i = 0; i < state_.x.size(); ++i)
    if (!std::isfinite(state_.x[i]))
      return StepStatus::Diverged("circulation state became non-finite", i, state_.x[i]);
  // A non-finite input (e.g. a cavity volume) may leave the states finite while a pressure or
  // flow is not: report it rather than publish NaN.
  for (Index i = 0; i < state_.pressure.size(); ++i) {
    if (!std::isfinite(state_.pressure[i])) {
      failed_compartment_ = static_cast<int>(i);
      return StepStatus::Diverged("compartment pressure is not finite (a non-finite input?)", i,
                                  state_.pressure[i]);
    }
  }
  for (Index i = 0; i < state_.flow.size(); ++i) {
    if (!std::isfinite(state_.flow[i])) {
      failed_connection_ = static_cast<int>(i);
      return StepStatus::Diverged("connection flow is not finite (a non-finite input?)", i,
                                  state_.flow[i]);
    }
  }
  if (params_.log_events) LogNewEvents();
  return StepStatus::Ok();
}

std::string Circulation::failure_detail() const {
  if (failed_compartment_ >= 0)
    return fmt::format("compartment '{}'",
                       circuit_.compartments()[static_cast<std::size_t>(failed_compartment_)].name);
  if (failed_connection_ >= 0)
    return fmt::format("connection '{}'",
                       circuit_.connections()[static_cast<std::size_t>(failed_connection_)].name);
  return {};
}

std::vector<std::string> Circulation::DescribeValveEvents() const {
  std::vector<std::string> lines;
  for (const ValveEvent& e : state_.events.get().Events())
    lines.push_back(fmt::format("t = {:.6f} s: {} {}", e.time, valve_name(e.valve),
                                e.state == ValveState::kOpen ? "opens" : "closes"));
  return lines;
}

void Circulation::LogNewEvents() {
  const ValveEventLog& events = state_.events.get();
  if (events.total() == state_.logged_events) return;
  for (const ValveEvent& e : events.EventsSince(state_.logged_events))
    Log().info("{}: t = {:.6f} s: valve {} {}", path(), e.time, valve_name(e.valve),
               e.state == ValveState::kOpen ? "opens" : "closes");
  state_.logged_events = events.total();
}

std::vector<SimObject::ProfileEntry> Circulation::ProfileBreakdown() const {
  return {{"adaptive steps accepted", static_cast<double>(state_.accepted), ""},
          {"adaptive steps rejected", static_cast<double>(state_.rejected), ""},
          {"derivative evaluations", static_cast<double>(state_.evaluations), ""},
          {"valve events", static_cast<double>(state_.events.get().total()), ""}};
}

void Circulation::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  const FieldTarget& f = targets_[static_cast<std::size_t>(id.value())];
  const int i = f.index;
  double value = 0;
  switch (f.quantity) {
    case Quantity::kPressure:
      value = state_.pressure[i];
      break;
    case Quantity::kVolume:
      value = state_.x[i];
      break;
    case Quantity::kElastance:
      value = circuit_.Elastance(i, time());
      break;
    case Quantity::kCavityVolume:
      value = circuit_.CavityVolume(i, time());
      break;
    case Quantity::kCavityRate:
      value = circuit_.CavityVolumeRate(i);
      break;
    case Quantity::kPressureInput:
      value = circuit_.ChamberPressure(i);
      break;
    case Quantity::kFlow:
      value = state_.flow[i];
      break;
    case Quantity::kPressureDrop: {
      const auto& s = circuit_.connections()[static_cast<std::size_t>(i)];
      value = s.from >= 0 ? state_.pressure[s.from] - state_.pressure[s.to]
                          : s.resistance * state_.flow[i];
      break;
    }
    case Quantity::kResistance:
      value = circuit_.resistance(i);
      break;
    case Quantity::kValveOpen:
      value = circuit_.valve_state(i) == ValveState::kOpen ? 1.0 : 0.0;
      break;
    case Quantity::kTotalVolume:
      value = total_volume();
      break;
    case Quantity::kValveEvents:
      value = static_cast<double>(state_.events.get().total());
      break;
    case Quantity::kSteps:
      value = static_cast<double>(state_.accepted);
      break;
  }
  out(0, 0) = value;
}

void Circulation::DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) {
  const FieldTarget& f = targets_[static_cast<std::size_t>(id.value())];
  const double value = in(0, 0);
  switch (f.quantity) {
    case Quantity::kCavityVolume:
      circuit_.SetCavityVolume(f.index, value, time());
      break;
    case Quantity::kCavityRate:
      circuit_.SetCavityVolumeRate(f.index, value, time());
      break;
    case Quantity::kFlow:
      circuit_.SetSourceFlow(f.index, value);
      break;
    case Quantity::kPressureInput:
      circuit_.SetChamberPressure(f.index, value);
      break;
    case Quantity::kResistance:
      circuit_.SetResistance(f.index, value);
      break;
    default:
      GIPSI_CHECK(false, "field is not writable");
  }
  UpdateOutputs(time());
}

}  // namespace gipsi
