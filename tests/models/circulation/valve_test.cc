// Valves as hybrid systems: the guard table, the event record, closure on flow reversal (with
// an inertance) versus on pressure crossover (without), and the object's behaviour on bad
// inputs at run time (a status, never an exception), determinism and field-driven sources.

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/base/state_value.h"
#include "gipsi/models/circulation/circuit.h"
#include "models/circulation/circulation_test_util.h"

namespace gipsi {
namespace {

TEST(ValveGuard, OpensOnPositivePressureDifferenceAndClosesOnReversal) {
  // Closed: the guard is Δp whatever the flow.
  EXPECT_GT(ValveGuard(ValveState::kClosed, false, 1.0, -5.0), 0);
  EXPECT_LT(ValveGuard(ValveState::kClosed, true, -1.0, 5.0), 0);
  // Open without inertance: closes when Δp < 0.
  EXPECT_GT(ValveGuard(ValveState::kOpen, false, -1.0, 0.0), 0);
  EXPECT_LT(ValveGuard(ValveState::kOpen, false, 1.0, 0.0), 0);
  // Open with inertance: closes when q < 0, even while Δp < 0 (flow still forward).
  EXPECT_LT(ValveGuard(ValveState::kOpen, true, -10.0, 1.0), 0);
  EXPECT_GT(ValveGuard(ValveState::kOpen, true, 10.0, -1.0), 0);
  EXPECT_EQ(NextValveState(ValveState::kOpen), ValveState::kClosed);
  EXPECT_EQ(NextValveState(ValveState::kClosed), ValveState::kOpen);
}

TEST(ValveEventLog, KeepsTheMostRecentEventsAndCountsAll) {
  ValveEventLog log(3);
  for (int k = 0; k < 5; ++k) log.Record({0.1 * k, k % 2, ValveState::kOpen});
  EXPECT_EQ(log.total(), 5);
  const auto kept = log.Events();
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_DOUBLE_EQ(kept[0].time, 0.2);
  EXPECT_DOUBLE_EQ(kept[2].time, 0.4);
  const auto since = log.EventsSince(4);
  ASSERT_EQ(since.size(), 1u);
  EXPECT_DOUBLE_EQ(since[0].time, 0.4);
  EXPECT_TRUE(log.EventsSince(5).empty());
}

/// The kept events of `a` and `b` are the same, in the same order.
void ExpectSameEvents(const ValveEventLog& a, const ValveEventLog& b) {
  const auto x = a.Events(), y = b.Events();
  ASSERT_EQ(x.size(), y.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    EXPECT_EQ(y[k].time, x[k].time) << k;
    EXPECT_EQ(y[k].valve, x[k].valve) << k;
    EXPECT_EQ(y[k].state, x[k].state) << k;
  }
}

/// `log` saved and restored into a fresh log of the same capacity.
ValveEventLog RoundTrip(const ValveEventLog& log, std::size_t capacity, std::size_t* bytes) {
  StateWriter out;
  WriteFields(out, log);
  *bytes = out.bytes().size();
  ValveEventLog restored(capacity);
  StateReader in(out.TakeBytes(), "the test log");
  ReadFields(in, restored);
  EXPECT_TRUE(in.at_end());
  EXPECT_EQ(restored.Inconsistency(8), "");
  return restored;
}

TEST(ValveEventLog, SavesOnlyTheEventsItHoldsAndRestoresThemInOrder) {
  // Partly filled: 4 events in room for 100,000. The state holds the 4 events (3 typed values
  // each plus headers), not the ring's room (1.6 MB).
  ValveEventLog partial;
  for (int k = 0; k < 4; ++k)
    partial.Record({0.1 * k, k, k % 2 ? ValveState::kOpen : ValveState::kClosed});
  std::size_t bytes = 0;
  ValveEventLog restored = RoundTrip(partial, 100000, &bytes);
  EXPECT_LT(bytes, 300u);
  EXPECT_EQ(restored.total(), 4);
  ASSERT_EQ(restored.Events().size(), 4u);
  ExpectSameEvents(partial, restored);
  // Wrapped: 7 events in room for 3, so the ring's slots are out of time order; the restored
  // log returns the last 3 oldest first and goes on wrapping where the original would.
  ValveEventLog wrapped(3);
  for (int k = 0; k < 7; ++k) wrapped.Record({0.1 * k, k, ValveState::kOpen});
  restored = RoundTrip(wrapped, 3, &bytes);
  wrapped.Record({0.7, 7, ValveState::kClosed});
  restored.Record({0.7, 7, ValveState::kClosed});
  EXPECT_EQ(restored.total(), 8);
  ASSERT_EQ(restored.Events().size(), 3u);
  ExpectSameEvents(wrapped, restored);
  EXPECT_EQ(restored.Events()[0].valve, 5);
}

TEST(ValveEventLog, AStateThatCannotBeThisLogsIsNamed) {
  // A state read into a log with room for fewer events than were kept (another scene's
  // checkpoint): the read itself is typed and succeeds, the check names the mismatch.
  ValveEventLog other(8);
  for (int k = 0; k < 5; ++k) other.Record({0.1 * k, 0, ValveState::kOpen});
  StateWriter more;
  WriteFields(more, other);
  ValveEventLog log(3);
  StateReader in(more.TakeBytes(), "other.gck");
  ReadFields(in, log);
  EXPECT_EQ(log.Inconsistency(1), "5 valve events kept, more than the log's capacity 3");
  // An event naming a valve the circuit does not have, or a state that is neither open nor
  // closed (a corrupted byte).
  ValveEventLog bad(4);
  bad.Record({0.1, 2, ValveState::kOpen});
  EXPECT_EQ(bad.Inconsistency(2), "valve event 0 names valve 2 of 2");
  ValveEventLog garbled(4);
  garbled.Record({0.1, 0, static_cast<ValveState>(7)});
  EXPECT_EQ(garbled.Inconsistency(1), "valve event 0 has no valve state 7");
}

// A chamber (cosine elastance) ejects through a valve into a reservoir at 80 mmHg. Integrated
// with the raw Circuit and AdaptiveOde so the state at the closing event can be inspected:
// with an inertance the valve closes when the flow reaches 0 — after the pressure difference
// has already turned negative (blood decelerating against an adverse gradient) — and without
// one it closes where Δp crosses 0 (and q = Δp/R with it). Both located to 1e-12 s, so q resp.
// Δp at the event are zero to (rate of change) × 1e-12 s plus the solution error.
void RunEjection(bool inertial, double& dp_at_close, double& q_at_close) {
  CompartmentSpec lv;
  lv.name = "lv";
  lv.kind = CompartmentSpec::Kind::kChamber;
  lv.e_max = 2.0 * kMmHg / kMl;
  lv.e_min = 0.1 * kMmHg / kMl;
  lv.activation.shape = Activation::Shape::kCosine;
  lv.activation.period = 1.0;
  lv.activation.contraction = 0.3;
  lv.activation.relaxation = 0.2;
  lv.initial_volume = 100 * kMl;
  CompartmentSpec aorta;
  aorta.name = "aorta";
  aorta.kind = CompartmentSpec::Kind::kReservoir;
  aorta.reservoir_pressure = 80 * kMmHg;
  ConnectionSpec valve;
  valve.name = "aortic";
  valve.kind = ConnectionSpec::Kind::kValve;
  valve.from = 0;
  valve.to = 1;
  valve.resistance = 0.05 * kMmHg / kMl;
  valve.inertance = inertial ? 0.002 * kMmHg / kMl : 0.0;
  CircuitState state;  // the valve states and inputs the circuit reads and changes
  Circuit circuit({lv, aorta}, {valve}, state);
  VecX x = circuit.InitialState();
  circuit.InitialiseValves(0, x);
  ASSERT_EQ(circuit.valve_state(0), ValveState::kClosed);
  AdaptiveOde ode;
  AdaptiveOdeOptions options;
  options.relative_tolerance = 1e-10;
  options.absolute_tolerance = 1e-15;
  options.event_tolerance = 1e-12;
  options.max_step = 1e-3;
  ode.Prepare(circuit.ode_size(), 1, options);
  double t = 0;
  int events = 0;
  VecX p(2), q(1);
  while (t < 1.0) {
    const auto result = ode.Integrate(OdeView(circuit), t, 1.0, x, &circuit.guards());
    ASSERT_TRUE(result.ok());
    if (result.outcome != AdaptiveOdeResult::Outcome::kEvent) break;
    ++events;
    if (circuit.valve_state(0) == ValveState::kOpen) {  // about to close: inspect
      circuit.CalcPressures(t, x, p);
      circuit.CalcFlows(t, x, p, q);
      dp_at_close = p[0] - p[1];
      q_at_close = q[0];
    }
    circuit.SwitchValve(0, x);
  }
  EXPECT_EQ(events, 2);  // opens during contraction, closes during relaxation
  EXPECT_EQ(circuit.valve_state(0), ValveState::kClosed);
}

TEST(Valves, InertialValveClosesOnFlowReversalAfterThePressureCrossover) {
  double dp = 0, q = 0;
  RunEjection(true, dp, q);
  EXPECT_LT(std::abs(q), 1e-9 * kMl);  // flow ~ 0 (peak flows are ~ 500 mL/s)
  EXPECT_LT(dp, -1.0 * kMmHg);         // the gradient had reversed by more than 1 mmHg
}

TEST(Valves, ValveWithoutInertanceClosesOnPressureCrossover) {
  double dp = 0, q = 0;
  RunEjection(false, dp, q);
  EXPECT_LT(std::abs(dp), 1e-6 * kMmHg);
  EXPECT_NEAR(q, dp / (0.05 * kMmHg / kMl), 1e-20);
}

// A chamber driven by pressure (the multiplier formulation of a 3-D coupling: the pressure is
// written, the volume integrates the flows) ejecting through a valve into a reservoir:
// p = 100 mmHg against 80 mmHg through R = 0.1 mmHg·s/mL is q = 200 mL/s, so V falls linearly
// (exactly, to round-off: the derivative is constant). Writing 70 mmHg makes the open valve's
// guard positive: it closes at the start of the next step (an event at that time) and the
// volume stays put.
TEST(PressureDrivenChamber, VolumeIntegratesTheFlowsAndValvesFollowTheWrittenPressure) {
  SceneHolder holder(R"({
    "objects": {"heart": {"type": "Circulation", "dt": "1 ms", "log_events": false,
      "compartments": {
        "lv": {"type": "chamber", "driven_by": "pressure", "volume": "120 mL",
               "pressure": "100 mmHg"},
        "aorta": {"type": "reservoir", "pressure": "80 mmHg"}},
      "connections": {
        "aortic": {"type": "valve", "from": "lv", "to": "aorta",
                   "resistance": "0.1 mmHg*s/mL"}}}},
    "schedule": {"end": "0.1 s"}})");
  Circulation& heart = holder.Object("heart");
  EXPECT_EQ(heart.valve_state(0), ValveState::kOpen);
  for (int k = 0; k < 100; ++k) ASSERT_TRUE(heart.Step(1e-3).ok());
  EXPECT_NEAR(heart.volume(0), 120 * kMl - 200 * kMl * 0.1, 1e-13 * 120 * kMl);
  EXPECT_NEAR(heart.flow(0), 200 * kMl, 1e-12 * 200 * kMl);
  heart.WriteField(heart.FindField("lv_pressure_input"),
                   Eigen::MatrixXd::Constant(1, 1, 70 * kMmHg));
  EXPECT_DOUBLE_EQ(heart.pressure(0), 70 * kMmHg);
  const double v = heart.volume(0);
  ASSERT_TRUE(heart.Step(1e-3).ok());
  EXPECT_EQ(heart.valve_state(0), ValveState::kClosed);
  ASSERT_EQ(heart.valve_events().total(), 1);
  EXPECT_NEAR(heart.valve_events().Events()[0].time, 0.1, 1e-15);
  EXPECT_EQ(heart.volume(0), v);
  EXPECT_EQ(heart.flow(0), 0.0);
}

const char* kSourceScene = R"({
  "objects": {"blood": {"type": "Circulation", "dt": "1 ms", "log_events": false,
    "compartments": {
      "lv": {"type": "chamber", "driven_by": "volume", "volume": "120 mL", "pressure": "10 mmHg"},
      "aorta": {"type": "compliance", "compliance": "1.2 mL/mmHg", "pressure": "80 mmHg"},
      "veins": {"type": "reservoir", "pressure": "5 mmHg"}},
    "connections": {
      "aortic": {"type": "valve", "from": "lv", "to": "aorta", "resistance": "0.05 mmHg*s/mL"},
      "infusion": {"type": "source", "to": "veins", "flow": {"waveform": "field"}},
      "peripheral": {"type": "resistor", "from": "aorta", "to": "veins",
                     "resistance": "1 mmHg*s/mL"}}}},
  "schedule": {"end": "0.1 s"}
})";

// A field-driven source adds exactly what was written times the time (it is the only flow
// into or out of the closed system), to round-off.
TEST(CirculationFields, FieldSourceAddsVolumeExactly) {
  SceneHolder holder(kSourceScene);
  Circulation& blood = holder.Object("blood");
  const double v0 = blood.total_volume();
  blood.WriteField(blood.FindField("infusion_flow"), Eigen::MatrixXd::Constant(1, 1, 2 * kMl));
  for (int k = 0; k < 100; ++k) ASSERT_TRUE(blood.Step(1e-3).ok());
  EXPECT_NEAR(blood.total_volume() - v0, 2 * kMl * 0.1, 1e-14 * v0);
}

// A non-finite input does not throw and is not published silently: the step reports
// divergence naming the compartment whose pressure it made non-finite.
TEST(CirculationFields, NonFiniteInputIsAStatusNotAnException) {
  SceneHolder holder(kSourceScene);
  Circulation& blood = holder.Object("blood");
  blood.WriteField(blood.FindField("lv_cavity_volume"),
                   Eigen::MatrixXd::Constant(1, 1, std::numeric_limits<double>::quiet_NaN()));
  StepStatus status;
  EXPECT_NO_THROW(status = blood.Step(1e-3));
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(status.code, StepStatus::Code::kDiverged);
  EXPECT_EQ(blood.failure_detail(), "compartment 'lv'");
}

// Same scene, same inputs: bit-identical states (no hidden state or threading in the step).
TEST(CirculationFields, IsDeterministic) {
  const std::string scene = R"({
    "objects": {"blood": {"type": "Circulation", "preset": "closed_loop", "dt": "1 ms",
                          "log_events": false}},
    "schedule": {"end": "1 s"}})";
  SceneHolder a(scene), b(scene);
  for (int k = 0; k < 1000; ++k) {
    ASSERT_TRUE(a.Object("blood").Step(1e-3).ok());
    ASSERT_TRUE(b.Object("blood").Step(1e-3).ok());
  }
  EXPECT_EQ(a.Object("blood").state(), b.Object("blood").state());
  EXPECT_EQ(a.Object("blood").valve_events().total(), b.Object("blood").valve_events().total());
}

}  // namespace
}  // namespace gipsi
