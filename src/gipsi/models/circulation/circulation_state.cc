/// @file
/// Circulation checkpoints: the ODE state (volumes, inertial flows), the valve states and the
/// inputs written by connectors or events (cavity volumes and their rates, chamber pressures,
/// source flows), the adaptive integrator's step-size controller and dense output, the valve
/// event log and the counters. Pressures and flows are outputs recomputed from the state but
/// are saved too, so probes read the same values before the first step after a restore.

#include <algorithm>
#include <cstdint>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/state.h"
#include "gipsi/models/circulation/circuit.h"
#include "gipsi/models/circulation/circulation.h"
#include "gipsi/models/circulation/valve.h"
#include "gipsi/numerics/adaptive_ode.h"

namespace gipsi {

// Only the slots in use are saved, field by field (no padding bytes): a log with room for
// 100,000 events holds a few hundred in a typical run, and saving the whole ring made it 70 % of
// the heart's state (1.6 MB of 2.3 MB per roll-back snapshot). Slots not saved are never read
// before they are written again (EventsSince reads the last min(total, capacity) events).
void ValveEventLog::SaveState(StateWriter& out) const {
  out.BeginSection("ValveEventLog", 2);
  const std::size_t used = static_cast<std::size_t>(
      std::min<std::int64_t>(total_, static_cast<std::int64_t>(ring_.size())));
  std::vector<double> times(used);
  std::vector<std::int32_t> valves(used);
  std::vector<std::uint8_t> states(used);
  for (std::size_t k = 0; k < used; ++k) {
    times[k] = ring_[k].time;
    valves[k] = ring_[k].valve;
    states[k] = static_cast<std::uint8_t>(ring_[k].state);
  }
  out.WriteInt(total_);
  out.WriteArray(times);
  out.WriteArray(valves);
  out.WriteArray(states);
  out.EndSection();
}

void ValveEventLog::RestoreState(StateReader& in) {
  in.BeginSection("ValveEventLog", 2);
  const std::int64_t total = in.ReadInt();
  if (total < 0) in.Fail(fmt::format("the valve event log: a negative count {}", total));
  std::vector<double> times(static_cast<std::size_t>(
      std::min<std::int64_t>(total, static_cast<std::int64_t>(ring_.size()))));
  std::vector<std::int32_t> valves(times.size());
  std::vector<std::uint8_t> states(times.size());
  in.ReadArrayExact(times, "the valve event times");
  in.ReadArrayExact(valves, "the valve event valves");
  in.ReadArrayExact(states, "the valve event states");
  in.EndSection();
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (states[k] > static_cast<std::uint8_t>(ValveState::kOpen))
      in.Fail(
          fmt::format("the valve event log: event {} has no valve state {}", k, int(states[k])));
    ring_[k] = {times[k], valves[k], static_cast<ValveState>(states[k])};
  }
  total_ = total;
}

void Circuit::SaveState(StateWriter& out) const {
  out.WriteArray(states_);
  out.WriteArray(cavity_volume_);
  out.WriteArray(cavity_rate_);
  out.WriteArray(cavity_time_);
  out.WriteArray(chamber_pressure_);
  out.WriteArray(source_value_);
}

void Circuit::RestoreState(StateReader& in) {
  in.ReadArrayExact(states_, "the valve states");
  in.ReadArrayExact(cavity_volume_, "the cavity volumes");
  in.ReadArrayExact(cavity_rate_, "the cavity volume rates");
  in.ReadArrayExact(cavity_time_, "the cavity input times");
  in.ReadArrayExact(chamber_pressure_, "the chamber pressures");
  in.ReadArrayExact(source_value_, "the source flows");
}

void AdaptiveOde::SaveState(StateWriter& out) const {
  for (const VecX& k : k_) out.WriteMatrix(k);
  for (const VecX* v : {&x_old_, &x_new_, &stage_, &err_, &g_old_, &g_new_, &g_probe_, &g_prev_,
                        &g_right_, &dense_})
    out.WriteMatrix(*v);
  out.WriteDouble(t_old_);
  out.WriteDouble(h_old_);
  out.WriteDouble(h_);
  out.WriteBool(have_step_);
  out.WriteInt(n_);
}

void AdaptiveOde::RestoreState(StateReader& in) {
  for (VecX& k : k_) in.ReadMatrix(k);
  for (VecX* v : {&x_old_, &x_new_, &stage_, &err_, &g_old_, &g_new_, &g_probe_, &g_prev_,
                  &g_right_, &dense_})
    in.ReadMatrix(*v);
  t_old_ = in.ReadDouble();
  h_old_ = in.ReadDouble();
  h_ = in.ReadDouble();
  have_step_ = in.ReadBool();
  n_ = in.ReadInt();
}

void Circulation::SaveObjectState(StateWriter& out) const {
  out.WriteMatrix(x_);
  out.WriteMatrix(pressure_);
  out.WriteMatrix(flow_);
  circuit_.SaveState(out);
  ode_.SaveState(out);
  events_.SaveState(out);
  out.WriteInt(logged_events_);
  out.WriteInt(accepted_);
  out.WriteInt(rejected_);
  out.WriteInt(evaluations_);
}

void Circulation::RestoreObjectState(StateReader& in) {
  in.ReadMatrixExact(x_, "the circulation state");
  in.ReadMatrixExact(pressure_, "the compartment pressures");
  in.ReadMatrixExact(flow_, "the connection flows");
  circuit_.RestoreState(in);
  ode_.RestoreState(in);
  events_.RestoreState(in);
  logged_events_ = in.ReadInt();
  accepted_ = in.ReadInt();
  rejected_ = in.ReadInt();
  evaluations_ = in.ReadInt();
}

}  // namespace gipsi
