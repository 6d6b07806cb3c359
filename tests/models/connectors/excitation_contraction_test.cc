// ExcitationContraction: the exact twitch ODE, relaxing the muscle's own tension, the voltage →
// tension mapping between two different meshes (exact for linear fields), and its wiring errors.

#include "gipsi/models/connectors/excitation_contraction.h"

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;

// EP on a 10 × 6 × 4 mm box (5 × 3 × 2 cells), muscle (FemSolid) on a box inside it with a
// different, finer mesh (7 × 4 × 3 cells), so the tension is interpolated.
std::string SceneText(const std::string& connector) {
  return R"({
  "gipsi": 1,
  "meshes": {
    "ep_box": {"generate": "box", "min": [0, 0, 0], "max": [0.010, 0.006, 0.004], "cells": [5, 3, 2]},
    "muscle_box": {"generate": "box", "min": [0.001, 0.0005, 0.0005], "max": [0.009, 0.0055, 0.0035], "cells": [7, 4, 3]}
  },
  "objects": {
    "ep": {"type": "Monodomain", "domain": "ep_box", "dt": 0.001, "cell": {"model": "AlievPanfilov"}, "conductivity": 0.1},
    "muscle": {"type": "FemSolid", "domain": "muscle_box", "dt": 0.001, "gravity": [0, 0, 0],
               "material": {"law": "NeoHookean", "youngs_modulus": 1e4, "poisson_ratio": 0.4}}
  },
  "connectors": {"ec": )" +
         connector + R"(},
  "schedule": {"end": 0.001}
})";
}

struct Loaded {
  TypeRegistry registry;
  Scene scene;
};

std::unique_ptr<Loaded> Load(const std::string& connector) {
  auto loaded = std::make_unique<Loaded>();
  RegisterBuiltins(loaded->registry);
  loaded->scene = LoadSceneFromString(SceneText(connector), "scene.json", ".", loaded->registry);
  return loaded;
}

const std::string kConnector =
    R"({"type": "ExcitationContraction", "from": "ep.V", "to": "muscle.nodal_active_tension",
        "v_rest": "-80 mV", "v_peak": "20 mV", "gain": "40 kPa", "rise_rate": "8 1/s",
        "decay_rate": "25 1/s"})";

// With V linear in space and above threshold everywhere, a long interval (e^{−8·10} ≈ 2e-35)
// leaves T_a = k u(V(x)), linear in x; barycentric interpolation reproduces linear fields, so
// every muscle node gets it to round-off although the meshes differ.
TEST(ExcitationContraction, MapsALinearFieldExactlyBetweenMeshes) {
  auto loaded = Load(kConnector);
  Kernel& kernel = *loaded->scene.kernel;
  SimObject& ep = kernel.FindObject("ep");
  SimObject& muscle = kernel.FindObject("muscle");
  auto v_of = [](const Vec3& x) { return -60 + 4000 * x.x() - 2000 * x.y() + 3000 * x.z(); };
  Eigen::MatrixXd v(1, ep.domain().num_nodes());
  for (Index i = 0; i < v.cols(); ++i) v(0, i) = v_of(ep.domain().nodes.col(i));
  ep.WriteField(ep.FindField("V"), v);
  Connector& ec = kernel.coordinator().connector(0);
  ASSERT_TRUE(ec.Fire(0.0).ok());
  ASSERT_TRUE(ec.Fire(10.0).ok());
  Eigen::MatrixXd ta(1, muscle.domain().num_nodes());
  muscle.ReadField(muscle.FindField("nodal_active_tension"), ta);
  for (Index i = 0; i < ta.cols(); ++i) {
    const double u = (v_of(muscle.domain().nodes.col(i)) + 80) / 100;
    ASSERT_GT(u, 0.05);
    EXPECT_NEAR(ta(0, i), 4e4 * u, 1e-8) << "node " << i;
  }
}

// Constant excitation: T_a(t) = k u (1 − e^{−rise t}) exactly, however the interval is cut;
// after repolarisation it decays as e^{−decay t}.
TEST(ExcitationContraction, IntegratesTheTwitchExactly) {
  auto loaded = Load(kConnector);
  Kernel& kernel = *loaded->scene.kernel;
  SimObject& ep = kernel.FindObject("ep");
  SimObject& muscle = kernel.FindObject("muscle");
  const FieldId v = ep.FindField("V");
  ep.WriteField(v, Eigen::MatrixXd::Constant(1, ep.domain().num_nodes(), 20.0));  // u = 1
  Connector& ec = kernel.coordinator().connector(0);
  double t = 0;
  for (double dt : {0.0, 0.013, 0.1, 0.037, 0.05}) ASSERT_TRUE(ec.Fire(t += dt).ok());
  Eigen::MatrixXd ta(1, muscle.domain().num_nodes());
  muscle.ReadField(muscle.FindField("nodal_active_tension"), ta);
  const double peak = 4e4 * (1 - std::exp(-8 * t));
  EXPECT_NEAR(ta.maxCoeff(), peak, 1e-9 * peak);
  EXPECT_NEAR(ta.minCoeff(), peak, 1e-9 * peak);
  ep.WriteField(v, Eigen::MatrixXd::Constant(1, ep.domain().num_nodes(), -80.0));  // rest
  ASSERT_TRUE(ec.Fire(t + 0.02).ok());
  muscle.ReadField(muscle.FindField("nodal_active_tension"), ta);
  EXPECT_NEAR(ta.maxCoeff(), peak * std::exp(-25 * 0.02), 1e-9 * peak);
}

// The tension is the muscle's: a firing relaxes it from the field's current value (here one
// written since the last firing, as a restored or moved muscle would hold), so T_a after Δt is
// k u + (T₀ − k u) e^{−ε Δt} from that T₀ at every node.
TEST(ExcitationContraction, RelaxesTheMusclesOwnTension) {
  auto loaded = Load(kConnector);
  Kernel& kernel = *loaded->scene.kernel;
  SimObject& ep = kernel.FindObject("ep");
  SimObject& muscle = kernel.FindObject("muscle");
  ep.WriteField(ep.FindField("V"), Eigen::MatrixXd::Constant(1, ep.domain().num_nodes(), -30.0));
  Connector& ec = kernel.coordinator().connector(0);
  ASSERT_TRUE(ec.Fire(0.0).ok());
  const FieldId tension = muscle.FindField("nodal_active_tension");
  Eigen::MatrixXd t0(1, muscle.domain().num_nodes());
  for (Index i = 0; i < t0.cols(); ++i) t0(0, i) = 1e3 * static_cast<double>(i % 7);  // Pa
  muscle.WriteField(tension, t0);
  ASSERT_TRUE(ec.Fire(0.02).ok());
  Eigen::MatrixXd ta(1, t0.cols());
  muscle.ReadField(tension, ta);
  const double target = 4e4 * 0.5;  // u = (−30 + 80)/100, above the threshold: the rise rate
  for (Index i = 0; i < ta.cols(); ++i)
    EXPECT_NEAR(ta(0, i), target + (t0(0, i) - target) * std::exp(-8 * 0.02), 1e-9 * target)
        << "node " << i;
}

TEST(ExcitationContraction, BadWiringGetsAClearError) {
  auto error = [](const std::string& connector) {
    try {
      (void)Load(connector);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_THAT(error(R"({"type": "ExcitationContraction", "from": "ep.activated_fraction",
                        "to": "muscle.nodal_active_tension"})"),
              HasSubstr("'from' must be a readable scalar node field"));
  EXPECT_THAT(error(R"({"type": "ExcitationContraction", "from": "ep.V",
                        "to": "muscle.von_mises_stress"})"),
              HasSubstr("'to' must be a readable and writable scalar node or element field"));
  EXPECT_THAT(error(R"({"type": "ExcitationContraction", "from": "ep.V",
                        "to": "muscle.nodal_active_tension", "gain": "40 kPa/s"})"),
              HasSubstr("connectors.ec.gain"));
}

}  // namespace
}  // namespace gipsi
