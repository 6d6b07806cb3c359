#pragma once
/// @file
/// `Circulation`: the lumped (0D) blood circulation as a GiPSi simulation object — heart
/// chambers as time-varying elastances (or driven by a 3-D cavity's volume), vessels as
/// compliances, resistances and inertances, and valves as hybrid systems whose transitions are
/// located inside the step. See circuit.h for the equations and docs/circulation.md for the
/// scene keys, default parameters and their sources.
///
/// `Step(dt)` integrates with Dormand–Prince 5(4) (AdaptiveOde): as many adaptive sub-steps as
/// the tolerance needs, stopping at every valve event, switching the valve and restarting there.
/// It never throws; failures come back as a StepStatus.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/state_value.h"
#include "gipsi/core/cavity_law.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"
#include "gipsi/models/circulation/circuit.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Everything a Circulation is built from. Plain struct; copyable.
struct CirculationParams {
  std::vector<CompartmentSpec> compartments;
  std::vector<ConnectionSpec> connections;
  double relative_tolerance = 1e-7;
  /// Absolute tolerance of volumes [m³]; inertial flows use it per second [m³/s].
  double absolute_tolerance = 1e-12;
  double max_step = 0.005;                  ///< largest adaptive step [s]
  double event_tolerance = 1e-9;            ///< valve events located to this width in time [s]
  int max_events_per_step = 1000;           ///< more transitions in one Step is chattering: fail
  std::size_t event_log_capacity = 100000;  ///< valve events kept (the most recent)
  bool log_events = true;  ///< log each valve transition (info level) after the step
};

/// What evolves in a Circulation, as a state value type (gipsi/base/state_value.h;
/// docs/architecture.md, "Model versus state"): checkpoints save it and step retries copy it,
/// with nothing else. Pressures and flows are outputs recomputed from the rest but are kept, so
/// probes read the same values before the first step after a restore. Copyable.
struct CirculationState {
  static constexpr std::string_view kTag = "CirculationState";
  static constexpr std::uint32_t kVersion = 2;  // 2: writable resistances (circuit.resistance)

  VecX x;                ///< the ODE state [volumes…, inertial flows…]
  VecX pressure, flow;   ///< per compartment [Pa] and per connection [m³/s], at the object's time
  CircuitState circuit;  ///< valve states and the latest inputs
  AdaptiveOdeState ode;  ///< the integrator's step-size guess and last step
  /// The valve transitions; Stamped, so a retry snapshot copies it only after a step with one.
  Stamped<ValveEventLog> events;
  std::int64_t logged_events = 0;                            ///< events already written to the log
  std::int64_t accepted = 0, rejected = 0, evaluations = 0;  ///< adaptive steps, f evaluations

  template <class Self, class Visitor>
  static void Fields(Self& s, Visitor& v) {
    v("x", s.x, Shape::kFixed);
    v("pressure", s.pressure, Shape::kFixed);
    v("flow", s.flow, Shape::kFixed);
    v("circuit", s.circuit);
    v("ode", s.ode);
    v("events", s.events);
    v("logged_events", s.logged_events);
    v("accepted", s.accepted);
    v("rejected", s.rejected);
    v("evaluations", s.evaluations);
  }
};

/// Not copyable or movable (a SimObject).
class Circulation final : public SimObject, public LumpedChambers {
 public:
  /// Builds the circuit and sets each valve open or closed from the initial pressures.
  /// Preconditions as Circuit's (the factory checks the scene and throws InputError).
  Circulation(std::string name, CirculationParams params);

  [[nodiscard]] std::string_view type_name() const override { return "Circulation"; }
  [[nodiscard]] const Points& domain_positions() const override { return no_positions_; }

  [[nodiscard]] const Circuit& circuit() const { return circuit_; }
  /// Index of the compartment or connection called `name`, or −1.
  [[nodiscard]] int FindCompartment(std::string_view name) const;
  [[nodiscard]] int FindConnection(std::string_view name) const;
  /// Current pressure [Pa] and volume [m³] of compartment c; flow [m³/s] of connection c.
  [[nodiscard]] double pressure(int c) const { return state_.pressure[c]; }
  [[nodiscard]] double volume(int c) const { return state_.x[c]; }
  [[nodiscard]] double flow(int c) const { return state_.flow[c]; }
  /// Σ of every compartment's volume [m³] (conserved by the closed loop).
  [[nodiscard]] double total_volume() const;
  /// Current state of valve k (index into circuit().valves()) and its name.
  [[nodiscard]] ValveState valve_state(int k) const { return circuit_.valve_state(k); }
  [[nodiscard]] const std::string& valve_name(int k) const;
  /// The record of valve transitions (most recent event_log_capacity kept).
  [[nodiscard]] const ValveEventLog& valve_events() const { return state_.events.get(); }
  /// One line per kept event: "t = 0.123456 s: aortic opens".
  [[nodiscard]] std::vector<std::string> DescribeValveEvents() const;
  /// The full ODE state [volumes…, inertial flows…].
  [[nodiscard]] const VecX& state() const { return state_.x; }
  /// Adaptive steps accepted and rejected, derivative evaluations, since construction.
  [[nodiscard]] std::int64_t accepted_steps() const { return state_.accepted; }
  [[nodiscard]] std::int64_t rejected_steps() const { return state_.rejected; }
  [[nodiscard]] std::vector<ProfileEntry> ProfileBreakdown() const override;
  /// LumpedChambers (cavity_law.h), for the monolithic cavity coupling. The prediction
  /// integrates exactly as Step would: same steps, events located the same way.
  [[nodiscard]] int FindPressureDrivenChamber(std::string_view name) const override;
  [[nodiscard]] double chamber_volume(int c) const override { return volume(c); }
  void SetChamberVolume(int c, double volume) override { SetVolume(c, volume); }
  bool PredictChamberVolume(int c, double dt, double p, double& volume) override;
  /// Sets the blood volume of compartment `c` [m³] (before the first step: a 3-D cavity's
  /// volume), and re-initialises the valves from the new pressures.
  void SetVolume(int c, double volume);
  /// Checkpoints: the bound CirculationState, checked after reading (the valve event log's
  /// counts, states and valve indices).
  void RestoreObjectState(StateReader& in) override;
  /// After a failed step: the compartment or connection whose value was not finite, if any.
  [[nodiscard]] std::string failure_detail() const override;

 protected:
  StepStatus DoStep(double t, double dt) override;
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

 private:
  enum class Quantity {
    // compartments
    kPressure,
    kVolume,
    kElastance,
    kCavityVolume,
    kCavityRate,
    kPressureInput,
    // connections
    kFlow,
    kPressureDrop,
    kResistance,
    kValveOpen,
    // global
    kTotalVolume,
    kValveEvents,
    kSteps,
  };
  struct FieldTarget {
    Quantity quantity;
    int index;
  };
  void Declare(FieldInfo info, Quantity quantity, int index);
  /// Integrates x over [t, t + dt] from the integrator state `memory`, switching valves at
  /// located events (recorded in the state's log if `record`); the status says why it stopped
  /// early.
  StepStatus Integrate(AdaptiveOdeState& memory, double t, double dt, VecX& x, bool record);
  void UpdateOutputs(double t);
  void LogNewEvents();

  CirculationParams params_;
  CirculationState state_;  // before circuit_, which refers to state_.circuit
  Circuit circuit_;
  AdaptiveOde ode_;  // the integrator: options and work space (its memory is in the states)
  // Scratch of PredictChamberVolume (a trial integration from the current state): not state.
  AdaptiveOdeState trial_ode_;
  VecX trial_x_;
  std::vector<ValveState> trial_valves_;
  int failed_compartment_ = -1, failed_connection_ = -1;  // of the last failed step
  std::vector<FieldTarget> targets_;                      // by field id
  Points no_positions_ = Points(3, 0);
};

/// Registers the "Circulation" object type.
void RegisterCirculation(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
