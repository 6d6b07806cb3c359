#pragma once
/// @file
/// Heart valves as hybrid systems (the GiPSi paper's "valves as finite-state machines"): each
/// valve is open or closed; its guard is a continuous function of the circuit state whose upward
/// zero crossing, located inside an integration step, fires the one transition out of the
/// current state:
///   closed → open   when the pressure difference Δp = p_from − p_to rises through 0;
///   open → closed   when the flow q falls through 0 (valves with an inertance, where q is a
///                   state), or when Δp falls through 0 (valves without one, where q = Δp/R).
/// A closed valve carries no flow at all (not a small leak): the circuit changes its equations.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The discrete state of a valve.
enum class ValveState : std::uint8_t { kClosed, kOpen };

/// "open" or "closed".
std::string_view ToString(ValveState state);

/// The guard of a valve in `state`: the transition fires when it crosses 0 upward.
/// `dp` = p_from − p_to [Pa], `q` the flow from → to [m³/s] (meaningful for inertial valves).
[[nodiscard]] constexpr double ValveGuard(ValveState state, bool inertial, double dp, double q) {
  if (state == ValveState::kClosed) return dp;
  return inertial ? -q : -dp;
}

/// The state a transition leads to.
[[nodiscard]] constexpr ValveState NextValveState(ValveState state) {
  return state == ValveState::kClosed ? ValveState::kOpen : ValveState::kClosed;
}

/// One valve transition: when, which valve (index among the circuit's valves), and the new state.
struct ValveEvent {
  double time = 0;  ///< [s]
  int valve = -1;
  ValveState state = ValveState::kClosed;

  template <class Self, class Visitor>
  static void Fields(Self& s, Visitor& v) {
    v("time", s.time);
    v("valve", s.valve);
    v("state", s.state);
  }
};

/// The record of valve transitions: a ring keeping the most recent `capacity` events (its
/// storage reserved up front, so recording never allocates), and the total count. A state
/// value type (gipsi/base/state_value.h) whose fields are the kept events and the count: a copy
/// moves only the events recorded, not the whole capacity. Copyable and movable.
class ValveEventLog {
 public:
  explicit ValveEventLog(std::size_t capacity = 100000);
  /// Appends an event (dropping the oldest when full).
  void Record(const ValveEvent& event);
  /// Events recorded since construction (including dropped ones).
  [[nodiscard]] std::int64_t total() const { return total_; }
  /// The kept events, oldest first (allocates the returned vector).
  [[nodiscard]] std::vector<ValveEvent> Events() const;
  /// The kept events with index ≥ `first` in the total numbering (for "what is new since").
  [[nodiscard]] std::vector<ValveEvent> EventsSince(std::int64_t first) const;
  [[nodiscard]] std::size_t capacity() const { return capacity_; }
  /// Why a log read from a checkpoint cannot be this one's (more kept events than the
  /// capacity, a count that disagrees with them, an unknown valve state or a valve index
  /// outside [0, num_valves)); empty if it can.
  [[nodiscard]] std::string Inconsistency(int num_valves) const;

  template <class Self, class Visitor>
  static void Fields(Self& s, Visitor& v) {
    v("events", s.ring_);
    v("total", s.total_);
  }

 private:
  std::size_t capacity_;
  std::vector<ValveEvent> ring_;  // min(total_, capacity_) events; event j at j % capacity_
  std::int64_t total_ = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
