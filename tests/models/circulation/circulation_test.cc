// The lumped circulation: Windkessel closed forms, event location on a known crossing, the
// volume-driven chamber against its closed form, and clear errors for bad scene input. The
// closed loop with the default parameters is in closed_loop_test.cc.

#include <cmath>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/circulation/circulation.h"
#include "models/circulation/circulation_test_util.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

// Windkessel parameters (SI) used below: R_p = 1 mmHg·s/mL, C = 1.5 mL/mmHg, R_c = 0.05
// mmHg·s/mL, venous pressure 5 mmHg.
const double kRp = 1.0 * kMmHg / kMl;
const double kC = 1.5 * kMl / kMmHg;
const double kRc = 0.05 * kMmHg / kMl;
const double kPv = 5 * kMmHg;

std::string WindkesselScene(const std::string& flow) {
  return R"({
  "objects": {"wk": {"type": "Circulation", "dt": "1 ms", "log_events": false,
    "tolerance": {"relative": 1e-10, "absolute": "1e-9 mL"},
    "compartments": {
      "arteries": {"type": "compliance", "compliance": "1.5 mL/mmHg", "pressure": "80 mmHg"},
      "veins": {"type": "reservoir", "pressure": "5 mmHg"}},
    "connections": {
      "inflow": {"type": "source", "to": "arteries", "resistance": "0.05 mmHg*s/mL",
                 "flow": )" +
         flow + R"(},
      "peripheral": {"type": "resistor", "from": "arteries", "to": "veins",
                     "resistance": "1 mmHg*s/mL"}}}},
  "schedule": {"end": "5 s"}
})";
}

// 3-element Windkessel under a prescribed inflow q(t) = Q_m + Q_a sin(ωt):
//   C dP/dt = q − (P − P_v)/R_p,  P_in = P + R_c q.
// With u = P − P_v − R_p Q_m and τ = R_p C, τ u' = −u + R_p Q_a sin ωt, so
//   u(t) = u_p(t) + (u(0) − u_p(0)) e^{−t/τ},  u_p = R_p Q_a (sin ωt − ωτ cos ωt)/(1 + ω²τ²).
// The integrator runs at rtol 1e-10 (volumes ~1e-4 m³, atol 1e-15 m³); this linear, stable
// problem does not amplify local errors (τ = 1.5 s), so 1e-8 relative to the pressure scale
// (1e-2 Pa on ~1e4 Pa) bounds the global error with a wide margin. Checked every 1 ms over 5 s.
TEST(Windkessel, SinusoidalInflowMatchesClosedForm) {
  const double qm = 90 * kMl, qa = 60 * kMl, period = 0.8;
  SceneHolder holder(WindkesselScene(R"({"waveform": "sine", "mean": "90 mL/s",
                                         "amplitude": "60 mL/s", "period": "0.8 s"})"));
  Circulation& wk = holder.Object("wk");
  const int arteries = wk.FindCompartment("arteries");
  const int inflow = wk.FindConnection("inflow");
  const FieldId drop = wk.FindField("inflow_pressure_drop");
  const double tau = kRp * kC, w = 2 * std::numbers::pi / period;
  auto exact = [&](double t) {
    auto up = [&](double s) {
      return kRp * qa * (std::sin(w * s) - w * tau * std::cos(w * s)) / (1 + w * w * tau * tau);
    };
    const double u0 = 80 * kMmHg - kPv - kRp * qm;
    return kPv + kRp * qm + up(t) + (u0 - up(0)) * std::exp(-t / tau);
  };
  double worst = 0, worst_inlet = 0;
  Eigen::MatrixXd value(1, 1);
  for (int k = 1; k <= 5000; ++k) {
    ASSERT_TRUE(wk.Step(1e-3).ok());
    const double t = wk.time();
    worst = std::max(worst, std::abs(wk.pressure(arteries) - exact(t)));
    const double q = qm + qa * std::sin(w * t);
    EXPECT_NEAR(wk.flow(inflow), q, 1e-12 * qm);
    wk.ReadField(drop, value);
    worst_inlet =
        std::max(worst_inlet, std::abs(wk.pressure(arteries) + value(0, 0) - (exact(t) + kRc * q)));
  }
  EXPECT_LT(worst, 1e-8 * 100 * kMmHg) << worst;
  EXPECT_LT(worst_inlet, 1e-8 * 100 * kMmHg) << worst_inlet;
}

// A constant inflow charges the compliance exponentially toward P_v + R_p Q:
// P(t) = P_v + R_p Q + (P0 − P_v − R_p Q) e^{−t/τ}. Same tolerance reasoning as above.
TEST(Windkessel, ConstantInflowMatchesClosedForm) {
  SceneHolder holder(WindkesselScene(R"("100 mL/s")"));
  Circulation& wk = holder.Object("wk");
  const int arteries = wk.FindCompartment("arteries");
  const double q = 100 * kMl, tau = kRp * kC;
  double worst = 0;
  for (int k = 1; k <= 3000; ++k) {
    ASSERT_TRUE(wk.Step(1e-3).ok());
    const double t = wk.time();
    const double exact = kPv + kRp * q + (80 * kMmHg - kPv - kRp * q) * std::exp(-t / tau);
    worst = std::max(worst, std::abs(wk.pressure(arteries) - exact));
  }
  EXPECT_LT(worst, 1e-8 * 100 * kMmHg) << worst;
}

// A written resistance acts from the next step: after R_p is doubled at t1 = 1.5 s, the
// pressure relaxes from P(t1) toward P_v + 2 R_p Q with τ' = 2 R_p C (the closed form above
// with the new R). It is state: a checkpoint taken after the write continues bitwise in a fresh
// scene. Same tolerance reasoning as above.
TEST(Windkessel, AWrittenResistanceActsAndIsCheckpointed) {
  SceneHolder holder(WindkesselScene(R"("100 mL/s")"));
  Circulation& wk = holder.Object("wk");
  const int arteries = wk.FindCompartment("arteries");
  const FieldId r = wk.FindField("peripheral_resistance");
  EXPECT_EQ(wk.field_info(r).units, "Pa*s/m3");
  Eigen::MatrixXd value(1, 1);
  wk.ReadField(r, value);
  EXPECT_DOUBLE_EQ(value(0, 0), kRp);  // the scene's "1 mmHg*s/mL", converted
  for (int k = 1; k <= 1500; ++k) ASSERT_TRUE(wk.Step(1e-3).ok());
  const double t1 = wk.time(), p1 = wk.pressure(arteries), q = 100 * kMl;
  value(0, 0) = 2 * kRp;
  wk.WriteField(r, value);
  StateWriter saved;
  wk.SaveState(saved);
  double worst = 0;
  for (int k = 1; k <= 1500; ++k) {
    ASSERT_TRUE(wk.Step(1e-3).ok());
    const double target = kPv + 2 * kRp * q;
    const double exact = target + (p1 - target) * std::exp(-(wk.time() - t1) / (2 * kRp * kC));
    worst = std::max(worst, std::abs(wk.pressure(arteries) - exact));
  }
  EXPECT_LT(worst, 1e-8 * 100 * kMmHg) << worst;

  SceneHolder fresh(WindkesselScene(R"("100 mL/s")"));
  Circulation& again = fresh.Object("wk");
  StateReader in(saved.bytes(), "saved");
  again.RestoreState(in);
  again.ReadField(r, value);
  EXPECT_EQ(value(0, 0), 2 * kRp);
  for (int k = 1; k <= 1500; ++k) ASSERT_TRUE(again.Step(1e-3).ok());
  EXPECT_EQ(again.pressure(arteries), wk.pressure(arteries));
}

// A resistance written as 0 (the connection has no inertance) fails the next step, naming the
// connection, instead of publishing an infinite flow.
TEST(Windkessel, AnUnusableWrittenResistanceFailsTheStepNamingTheConnection) {
  SceneHolder holder(WindkesselScene(R"("100 mL/s")"));
  Circulation& wk = holder.Object("wk");
  Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(1, 1);
  wk.WriteField(wk.FindField("peripheral_resistance"), zero);
  const StepStatus status = wk.Step(1e-3);
  EXPECT_FALSE(status.ok());
  EXPECT_THAT(status.what, HasSubstr("resistance"));
  EXPECT_EQ(wk.failure_detail(), "connection 'peripheral'");
  EXPECT_FALSE(wk.TryFindField("inflow_resistance").has_value());  // a source's R is not an input
}

// A chamber with both valves closed keeps its volume exactly (its derivative is 0), so its
// pressure is the known function E(t)(V − V0). With the cosine activation
// e = ½(1 − cos(π t/Tc)) it reaches the reservoir pressure P_r at
//   t* = (Tc/π) acos(1 − 2 e*),  e* = (P_r/(V − V0) − E_min)/(E_max − E_min),
// where the outlet valve must open. The event is located to the 1e-12 s event tolerance
// (the state is exact, so nothing else contributes): asserted to 2e-12 s.
TEST(Valves, OpeningIsLocatedAtTheKnownCrossingTime) {
  SceneHolder holder(R"({
  "objects": {"heart": {"type": "Circulation", "dt": "10 ms", "log_events": false,
    "event_tolerance": "1e-12 s",
    "compartments": {
      "lv": {"type": "chamber", "e_max": "2 mmHg/mL", "e_min": "0.1 mmHg/mL",
             "activation": {"shape": "cosine", "period": "1 s", "contraction": "0.3 s",
                            "relaxation": "0.2 s"},
             "volume": "100 mL"},
      "aorta": {"type": "reservoir", "pressure": "80 mmHg"}},
    "connections": {
      "aortic": {"type": "valve", "from": "lv", "to": "aorta", "resistance": "0.05 mmHg*s/mL"}}}},
  "schedule": {"end": "0.3 s"}
})");
  Circulation& heart = holder.Object("heart");
  EXPECT_EQ(heart.valve_state(0), ValveState::kClosed);
  for (int k = 0; k < 30; ++k) ASSERT_TRUE(heart.Step(0.01).ok());
  const auto events = heart.valve_events().Events();
  ASSERT_GE(events.size(), 1u);
  EXPECT_EQ(events[0].state, ValveState::kOpen);
  const double e_star = (0.8 - 0.1) / (2.0 - 0.1);
  const double t_star = 0.3 / std::numbers::pi * std::acos(1 - 2 * e_star);
  EXPECT_NEAR(events[0].time, t_star, 2e-12);
  EXPECT_EQ(heart.valve_state(0), ValveState::kOpen);
  EXPECT_EQ(heart.DescribeValveEvents()[0],
            fmt::format("t = {:.6f} s: aortic opens", events[0].time));
}

// A chamber driven by a cavity volume V_cav(t) = V0 − a t (the rate written to its field),
// emptying through R into a reservoir at P_r: with p = (V − V_cav)/C_c and V' = −(p − P_r)/R,
//   p(t) = P_r + R a + (p0 − P_r − R a) e^{−t/(R C_c)},
// so after a few R C_c the pressure is the Lagrange multiplier P_r + R a of the constraint
// V = V_cav, and the blood volume trails the cavity by C_c p. Tolerance as for the Windkessel.
TEST(VolumeDrivenChamber, PressureFollowsTheClosedForm) {
  SceneHolder holder(R"({
  "objects": {"heart": {"type": "Circulation", "dt": "0.1 ms", "log_events": false,
    "tolerance": {"relative": 1e-10, "absolute": "1e-9 mL"},
    "compartments": {
      "lv": {"type": "chamber", "driven_by": "volume", "coupling_compliance": "0.01 mL/mmHg",
             "volume": "120 mL", "pressure": "10 mmHg"},
      "aorta": {"type": "reservoir", "pressure": "80 mmHg"}},
    "connections": {
      "out": {"type": "resistor", "from": "lv", "to": "aorta", "resistance": "0.1 mmHg*s/mL"}}}},
  "schedule": {"end": "0.1 s"}
})");
  Circulation& heart = holder.Object("heart");
  const FieldId rate = heart.FindField("lv_cavity_volume_rate");
  const FieldId cavity = heart.FindField("lv_cavity_volume");
  const double a = 300 * kMl;  // 300 mL/s ejection
  heart.WriteField(rate, Eigen::MatrixXd::Constant(1, 1, -a));
  const double R = 0.1 * kMmHg / kMl, cc = 0.01 * kMl / kMmHg, pr = 80 * kMmHg;
  const double p0 = 10 * kMmHg;
  double worst = 0;
  Eigen::MatrixXd v(1, 1);
  for (int k = 1; k <= 1000; ++k) {
    ASSERT_TRUE(heart.Step(1e-4).ok());
    const double t = heart.time();
    const double exact = pr + R * a + (p0 - pr - R * a) * std::exp(-t / (R * cc));
    worst = std::max(worst, std::abs(heart.pressure(0) - exact));
  }
  EXPECT_LT(worst, 1e-8 * 100 * kMmHg) << worst;
  heart.ReadField(cavity, v);
  EXPECT_NEAR(v(0, 0), 120 * kMl - a * 0.1, 1e-18);
  EXPECT_NEAR(heart.volume(0), v(0, 0) + cc * heart.pressure(0), 1e-12 * 120 * kMl);
}

std::string SmallScene(const std::string& compartments, const std::string& connections) {
  return R"({"objects": {"blood": {"type": "Circulation", "dt": "1 ms",
    "compartments": {)" +
         compartments + R"(}, "connections": {)" + connections + R"(}}},
    "schedule": {"end": "1 ms"}})";
}

const std::string kTwo =
    R"("a": {"type": "compliance", "compliance": "1 mL/mmHg", "pressure": "10 mmHg"},
       "b": {"type": "reservoir", "pressure": "0 mmHg"})";

TEST(CirculationScene, BadInputGetsAClearError) {
  EXPECT_THAT(
      SceneError(SmallScene(
          R"("a": {"type": "compliance", "compliance": "-1 mL/mmHg", "pressure": "10 mmHg"})", "")),
      HasSubstr("scene.json: objects.blood.compartments.a.compliance: expected a positive "
                "quantity"));
  EXPECT_THAT(
      SceneError(SmallScene(
          kTwo, R"("r": {"type": "resistor", "from": "a", "to": "ventricle", "resistance": 1e6})")),
      HasSubstr("objects.blood.connections.r.to: unknown compartment 'ventricle'; the compartments "
                "are: a, b"));
  EXPECT_THAT(
      SceneError(SmallScene(
          kTwo, R"("r": {"type": "resistor", "from": "aa", "to": "b", "resistance": 1e6})")),
      HasSubstr("unknown compartment 'aa' (did you mean 'a'?)"));
  EXPECT_THAT(
      SceneError(SmallScene(
          R"("a": {"type": "compliance", "compliance": "1.5 mL", "pressure": "10 mmHg"})", "")),
      HasSubstr("objects.blood.compartments.a.compliance: \"1.5 mL\": 'mL' cannot be converted "
                "to m^3/Pa (another dimension)"));
  EXPECT_THAT(
      SceneError(SmallScene(
          kTwo, R"("r": {"type": "resistor", "from": "a", "to": "b", "resistance": "2 mmHg"})")),
      HasSubstr("'mmHg' cannot be converted to Pa*s/m^3"));
  EXPECT_THAT(SceneError(SmallScene(kTwo, R"("r": {"type": "resistor", "from": "a", "to": "b"})")),
              HasSubstr("objects.blood.connections.r: give a positive \"resistance\""));
  EXPECT_THAT(SceneError(SmallScene(
                  R"("lv": {"type": "chamber", "e_max": "0.1 mmHg/mL", "e_min": "1 mmHg/mL",
                           "volume": "100 mL"})",
                  "")),
              HasSubstr("objects.blood.compartments.lv.e_max: e_max"));
  EXPECT_THAT(SceneError(SmallScene(
                  R"("a": {"type": "compliance", "compliance": 1e-8, "volume": 1e-4,
                           "pressure": 1000})",
                  "")),
              HasSubstr("exactly one of \"volume\""));
  EXPECT_THAT(SceneError(SmallScene(
                  R"("a.b": {"type": "compliance", "compliance": 1e-8, "volume": 1e-4})", "")),
              HasSubstr("may only contain letters, digits and '_'"));
  EXPECT_THAT(SceneError(SmallScene(kTwo, R"("a": {"type": "resistor", "from": "a", "to": "b",
                                             "resistance": 1e6})")),
              HasSubstr("'a' names both a compartment and a connection"));
  EXPECT_THAT(SceneError(SmallScene(kTwo, R"("r": {"type": "resistor", "from": "a", "to": "b",
                                             "resistance": 1e6, "inertence": 1})")),
              HasSubstr("did you mean 'inertance'"));
  EXPECT_THAT(SceneError(R"({"objects": {"blood": {"type": "Circulation", "preset": "open_loop"}},
                            "schedule": {"end": 1}})"),
              HasSubstr("objects.blood.preset: expected one of"));
}

}  // namespace
}  // namespace gipsi
