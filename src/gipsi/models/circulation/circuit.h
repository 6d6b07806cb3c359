#pragma once
/// @file
/// The equations of a lumped (0D) circulation: compartments that hold blood (their volumes are
/// states) joined by connections that move it (resistors, valves, prescribed sources), with
/// optional inertances (their flows are states). All in SI: Pa, m³, m³/s, s.
///
///   dV_c/dt = Σ_{connections into c} q − Σ_{connections out of c} q
///   resistor or open valve without inertance:  q = (p_from − p_to) / R
///   resistor or open valve with inertance L:   L dq/dt = p_from − p_to − R q
///   closed valve:                              q = 0 (and dq/dt = 0)
///   source:                                    q = q(t) (a waveform or a written field)
///
/// Pressure laws: chamber p = E(t)(V − V0) with E(t) = E_min + (E_max − E_min) e(t); a chamber
/// driven by an external cavity volume V_cav(t) is a stiff compliance C_c between the blood
/// volume and the cavity, p = (V − V_cav(t)) / C_c (the penalty form of the constraint
/// V = V_cav, whose multiplier is p); a chamber driven by pressure takes p as given (written);
/// compliance p = (V − V0)/C; reservoir p = const (its volume counts what flowed in, so the total
/// is conserved in every circuit). Every flow leaves one compartment and enters another, so Σ V is
/// conserved to round-off.

#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/base/state_value.h"
#include "gipsi/models/circulation/activation.h"
#include "gipsi/models/circulation/valve.h"
#include "gipsi/numerics/adaptive_ode.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A blood-holding compartment. Plain struct; copyable.
struct CompartmentSpec {
  enum class Kind { kChamber, kCompliance, kReservoir };
  /// How a chamber's pressure is found: its own elastance, an external cavity volume, or an
  /// external pressure (then only its volume is integrated).
  enum class Drive { kElastance, kVolume, kPressure };
  std::string name;
  Kind kind = Kind::kCompliance;
  Drive drive = Drive::kElastance;
  double e_max = 0, e_min = 0;       ///< chamber elastances [Pa/m³]
  Activation activation;             ///< chamber activation e(t)
  double compliance = 0;             ///< compliance [m³/Pa]; for volume-driven chambers C_c
  double unstressed_volume = 0;      ///< V0 [m³] (chamber dead volume, vessel unstressed volume)
  double reservoir_pressure = 0;     ///< reservoir [Pa]
  double initial_volume = 0;         ///< V at t = 0 [m³] (blood volume; reservoirs: 0)
  double initial_cavity_volume = 0;  ///< volume-driven chambers: V_cav at t = 0 [m³]
  double initial_pressure = 0;       ///< pressure-driven chambers: p at t = 0 [Pa]
};

/// A prescribed flow q(t) [m³/s]. Plain struct; copyable.
struct FlowWaveform {
  enum class Kind { kConstant, kSine, kHalfSine, kField };
  Kind kind = Kind::kConstant;
  double mean = 0;       ///< constant value, or the sine's mean [m³/s]
  double amplitude = 0;  ///< sine amplitude; half-sine peak [m³/s]
  double period = 1;     ///< [s]
  double duration = 0;   ///< half-sine pulse length [s], ≤ period
  /// q(t); kField returns `field_value`.
  [[nodiscard]] double Evaluate(double t, double field_value) const;
};

/// A connection from one compartment to another. Plain struct; copyable.
struct ConnectionSpec {
  enum class Kind { kResistor, kValve, kSource };
  std::string name;
  Kind kind = Kind::kResistor;
  int from = -1;            ///< compartment index (−1 for a source: from outside)
  int to = -1;              ///< compartment index
  double resistance = 0;    ///< R [Pa·s/m³] (a source's R only gives its pressure drop)
  double inertance = 0;     ///< L [Pa·s²/m³]; 0: none
  double initial_flow = 0;  ///< inertial connections [m³/s]
  FlowWaveform source;      ///< kSource only
  [[nodiscard]] bool inertial() const { return inertance > 0 && kind != Kind::kSource; }
};

/// The circuit's discrete state and its latest inputs, as a state value type
/// (gipsi/base/state_value.h): every valve's state, and what connectors or events last wrote
/// (cavity volumes with their rates and times, chamber pressures, source flows). All sized by
/// the circuit. Copyable.
struct CircuitState {
  std::vector<ValveState> valves;  ///< per valve
  /// Per compartment: the driving cavity's volume [m³], its rate [m³/s] and when they were
  /// written [s]; the prescribed pressure of a pressure-driven chamber [Pa].
  std::vector<double> cavity_volume, cavity_rate, cavity_time, chamber_pressure;
  std::vector<double> source_value;  ///< per connection: a field-driven source's flow [m³/s]
  /// Per connection: R [Pa·s/m³], the spec's until written (`<name>_resistance`).
  std::vector<double> resistance;

  template <class Self, class Visitor>
  static void Fields(Self& s, Visitor& v) {
    v("valves", s.valves, Shape::kFixed);
    v("cavity_volume", s.cavity_volume, Shape::kFixed);
    v("cavity_rate", s.cavity_rate, Shape::kFixed);
    v("cavity_time", s.cavity_time, Shape::kFixed);
    v("chamber_pressure", s.chamber_pressure, Shape::kFixed);
    v("source_value", s.source_value, Shape::kFixed);
    v("resistance", s.resistance, Shape::kFixed);
  }
};

/// The circuit: specs and its ODE, reading and changing a CircuitState that lives elsewhere
/// (in the Circulation's state). An OdeSystem. Not copyable or movable (its guards refer to it).
/// CalcDerivative allocates nothing.
class Circuit {
 public:
  Circuit(const Circuit&) = delete;
  Circuit& operator=(const Circuit&) = delete;
  /// Sizes `state` for these specs and sets it to the specs' initial inputs (valves closed
  /// until InitialiseValves); `state` must outlive the circuit. Preconditions (checked): indices
  /// in range, positive parameters where needed (the scene factory reports bad input as
  /// InputError before this).
  Circuit(std::vector<CompartmentSpec> compartments, std::vector<ConnectionSpec> connections,
          CircuitState& state);

  [[nodiscard]] const std::vector<CompartmentSpec>& compartments() const { return compartments_; }
  [[nodiscard]] const std::vector<ConnectionSpec>& connections() const { return connections_; }
  [[nodiscard]] int num_compartments() const { return static_cast<int>(compartments_.size()); }
  [[nodiscard]] int num_connections() const { return static_cast<int>(connections_.size()); }
  /// Connection indices of the valves, in declaration order (valve k is
  /// connections()[valves()[k]]).
  [[nodiscard]] const std::vector<int>& valves() const { return valves_; }

  // --- OdeSystem: x = [V_0 … V_{C−1}, q of each inertial connection] ---
  [[nodiscard]] Index ode_size() const { return size_; }
  [[nodiscard]] Index ode_num_positions() const { return 0; }
  void CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const;
  /// The initial state (volumes and inertial flows of the specs).
  [[nodiscard]] VecX InitialState() const;
  /// Index in x of connection c's flow, or −1 if it is not a state.
  [[nodiscard]] Index flow_state(int c) const { return flow_state_[static_cast<std::size_t>(c)]; }

  /// Pressures of every compartment at (t, x) into `p` (size num_compartments()).
  void CalcPressures(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> p) const;
  /// Flows of every connection at (t, x) given the pressures `p`, into `q`.
  void CalcFlows(double t, Eigen::Ref<const VecX> x, Eigen::Ref<const VecX> p,
                 Eigen::Ref<VecX> q) const;
  /// Elastance of chamber compartment `c` at time t [Pa/m³] (0 for others).
  [[nodiscard]] double Elastance(int c, double t) const;

  // --- Valves (the hybrid part) ---
  [[nodiscard]] ValveState valve_state(int k) const {
    return s_.valves[static_cast<std::size_t>(k)];
  }
  /// Every valve's state (valve order), e.g. to undo a trial integration.
  [[nodiscard]] const std::vector<ValveState>& valve_states() const { return s_.valves; }
  void SetValveStates(const std::vector<ValveState>& states) { s_.valves = states; }
  /// Switches valve k to its next state; a closing inertial valve's flow state is set to 0.
  void SwitchValve(int k, Eigen::Ref<VecX> x);
  /// Sets every valve's state from the pressures at (t, x) without events: open where the
  /// guard of the closed state is positive (Δp > 0, or a positive inertial flow).
  void InitialiseValves(double t, Eigen::Ref<VecX> x);
  /// Guards of every valve at (t, x) (EventFunctions for AdaptiveOde).
  [[nodiscard]] const EventFunctions& guards() const { return guards_; }

  // --- External inputs ---
  /// Volume-driven chamber c: V_cav(t) = volume + rate (t − t_written).
  void SetCavityVolume(int c, double volume, double t_written);
  void SetCavityVolumeRate(int c, double rate, double t_written);
  [[nodiscard]] double CavityVolume(int c, double t) const;
  [[nodiscard]] double CavityVolumeRate(int c) const {
    return s_.cavity_rate[static_cast<std::size_t>(c)];
  }
  /// Pressure-driven chamber c: p (held until written again).
  void SetChamberPressure(int c, double p) { s_.chamber_pressure[static_cast<std::size_t>(c)] = p; }
  [[nodiscard]] double ChamberPressure(int c) const {
    return s_.chamber_pressure[static_cast<std::size_t>(c)];
  }
  /// Field-driven source connection c.
  void SetSourceFlow(int c, double q) { s_.source_value[static_cast<std::size_t>(c)] = q; }
  /// Connection c's resistance R [Pa·s/m³] (the spec's until set). Any value may be set; the
  /// owner checks it before stepping (ResistanceProblem).
  void SetResistance(int c, double r) { s_.resistance[static_cast<std::size_t>(c)] = r; }
  [[nodiscard]] double resistance(int c) const {
    return s_.resistance[static_cast<std::size_t>(c)];
  }
  /// The first connection (not a source) whose resistance cannot be used (R ≤ 0 where it has
  /// no inertance, R < 0 otherwise, or not finite), or −1.
  [[nodiscard]] int ResistanceProblem() const;

 private:
  class Guards final : public EventFunctions {
   public:
    explicit Guards(const Circuit* circuit) : circuit_(circuit) {}
    [[nodiscard]] int num_events() const override;
    void Calc(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> g) const override;
    const Circuit* circuit_;
  };

  std::vector<CompartmentSpec> compartments_;
  std::vector<ConnectionSpec> connections_;
  std::vector<int> valves_;
  std::vector<Index> flow_state_;
  CircuitState& s_;
  Index size_ = 0;
  Guards guards_{this};
  mutable VecX p_work_, q_work_;  // CalcDerivative/guards work space
};

}  // namespace gipsi
GIPSI_EXPORT_END
