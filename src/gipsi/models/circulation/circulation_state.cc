/// @file
/// Circulation checkpoints: the bound CirculationState (circulation.h) is written and read
/// generically; what a type check cannot see in a corrupted or foreign checkpoint (the valve
/// event log's counts, valve states and valve indices) is checked here.

#include <string>

#include <fmt/format.h>

#include "gipsi/base/state.h"
#include "gipsi/models/circulation/circulation.h"

namespace gipsi {

void Circulation::RestoreObjectState(StateReader& in) {
  SimObject::RestoreObjectState(in);
  const int num_valves = static_cast<int>(circuit_.valves().size());
  for (std::size_t k = 0; k < state_.circuit.valves.size(); ++k) {
    const ValveState v = state_.circuit.valves[k];
    if (v != ValveState::kClosed && v != ValveState::kOpen)
      in.Fail(fmt::format("valve '{}' has no state {}", valve_name(static_cast<int>(k)), int(v)));
  }
  const std::string log = state_.events.get().Inconsistency(num_valves);
  if (!log.empty()) in.Fail("the valve event log: " + log);
  if (state_.logged_events < 0 || state_.logged_events > state_.events.get().total())
    in.Fail(fmt::format("{} valve events logged of {}", state_.logged_events,
                        state_.events.get().total()));
}

}  // namespace gipsi
