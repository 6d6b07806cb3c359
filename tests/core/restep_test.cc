// Stepping again from a restored state: for every built-in object and connector type, a scene
// is run to t1, its state saved, run on to t2, restored to t1 and run to t2 again. Both runs to
// t2 must end in the same state and the same fields, bit for bit. This is what the kernel's
// retry policy (restore, then re-step with halved steps) and a checkpoint resume rely on, and
// it fails for any mutable member that is not part of the saved state but changes what the
// next step computes (a warm start, a kept factorisation's age, a contact's friction anchor, a
// haptic buffer): the second run starts from t1 with whatever the first run left at t2.
//
// The resume tests in checkpoint_test.cc restore into a *fresh* process; this one restores into
// the *same* objects after they ran ahead, so the two together cover both directions.
//
// The same property for the in-memory snapshots the retry policy copies (SimObject::
// TakeSnapshot, gipsi/base/object_state.h): restored twice from one snapshot, the scene must
// arrive at the same bits both times. A snapshot restore follows each type's cache rule (a
// FemSolid forgets its Newton hand-over), so the reference is a second restore, not the first
// run.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <Eigen/Core>

#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/core/aggregate.h"
#include "gipsi/core/kernel.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "test_paths.h"

namespace gipsi {
namespace {

/// The kernel's complete state (SaveState) as bytes.
std::string StateBytes(Kernel& kernel) {
  StateWriter out;
  kernel.SaveState(out);
  return out.TakeBytes();
}

/// Every readable field of every object and part, by "object/field", as raw bytes (so NaNs
/// and signed zeros compare exactly).
std::map<std::string, std::string> Fields(const Kernel& kernel) {
  std::map<std::string, std::string> fields;
  for (const auto& [path, object] : kernel.ObjectPaths()) {
    for (std::size_t i = 0; i < object->fields().size(); ++i) {
      const FieldId id(static_cast<std::int64_t>(i));
      const FieldInfo& info = object->field_info(id);
      if (!info.readable()) continue;
      Eigen::MatrixXd value(info.components, object->FieldCount(id));
      object->ReadField(id, value);
      fields[path + "/" + info.name] = std::string(reinterpret_cast<const char*>(value.data()),
                                                   sizeof(double) * std::size_t(value.size()));
    }
  }
  return fields;
}

/// Runs `scene` to t1, saves, runs to t2, restores t1's state into the same kernel and runs to
/// t2 again; both arrivals at t2 must be bitwise identical.
void ExpectRestepIsBitwise(const std::string& scene, double t1, double t2) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene loaded = LoadScene(std::string(GIPSI_SOURCE_DIR) + "/scenes/" + scene, registry);
  Kernel& kernel = *loaded.kernel;

  RunResult run = kernel.Run(t1);
  ASSERT_TRUE(run.ok()) << run.diagnostic;
  const std::string at_t1 = StateBytes(kernel);
  const std::int64_t steps_t1 = kernel.macro_steps();

  run = kernel.Run(t2);
  ASSERT_TRUE(run.ok()) << run.diagnostic;
  ASSERT_GT(kernel.macro_steps(), steps_t1) << "t2 must lie at least one macro step after t1";
  const auto first_fields = Fields(kernel);
  const std::string first = StateBytes(kernel);

  StateReader in(at_t1, scene + " at t1");
  kernel.RestoreState(in);
  ASSERT_EQ(kernel.macro_steps(), steps_t1);
  run = kernel.Run(t2);
  ASSERT_TRUE(run.ok()) << run.diagnostic;
  const auto second_fields = Fields(kernel);

  EXPECT_TRUE(StateBytes(kernel) == first)
      << scene << ": the state at t2 differs after restoring t1 and stepping again";
  ASSERT_EQ(first_fields.size(), second_fields.size());
  for (const auto& [name, bytes] : first_fields)
    EXPECT_TRUE(second_fields.at(name) == bytes)
        << scene << ": field " << name << " differs after restoring t1 and stepping again";
}

/// Runs `scene` to t1 and snapshots it (the kernel's part by checkpoint bytes, the objects' by
/// Coordinator::NewSnapshot), then twice: restores both and runs to t2. Both arrivals must be
/// bitwise identical, in the snapshot and in every field.
void ExpectSnapshotRestepIsBitwise(const std::string& scene, double t1, double t2) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene loaded = LoadScene(std::string(GIPSI_SOURCE_DIR) + "/scenes/" + scene, registry);
  Kernel& kernel = *loaded.kernel;
  RunResult run = kernel.Run(t1);
  ASSERT_TRUE(run.ok()) << run.diagnostic;
  const std::string kernel_at_t1 = StateBytes(kernel);
  const std::unique_ptr<ObjectState> at_t1 = kernel.coordinator().NewSnapshot();

  std::unique_ptr<ObjectState> arrivals[2];
  std::map<std::string, std::string> fields[2];
  run = kernel.Run(t2);  // run ahead first: the restores start from objects that went on
  ASSERT_TRUE(run.ok()) << run.diagnostic;
  for (int k = 0; k < 2; ++k) {
    StateReader in(kernel_at_t1, scene + " at t1");
    kernel.RestoreState(in);
    kernel.coordinator().RestoreSnapshot(*at_t1);
    run = kernel.Run(t2);
    ASSERT_TRUE(run.ok()) << run.diagnostic;
    fields[k] = Fields(kernel);
    arrivals[k] = kernel.coordinator().NewSnapshot();
  }
  EXPECT_EQ(arrivals[0]->FirstDifference(*arrivals[1]), "")
      << scene << ": stepping again from the same snapshot gave other bits";
  ASSERT_EQ(fields[0].size(), fields[1].size());
  for (const auto& [name, bytes] : fields[0])
    EXPECT_TRUE(fields[1].at(name) == bytes)
        << scene << ": field " << name << " differs between two restores of one snapshot";
}

/// Every built-in object and connector type, in the scenes of the tests below.
const struct {
  const char* scene;
  double t1, t2;
} kEveryType[] = {{"hanging_sheet.json", 1.0, 1.6},
                  {"block_drop.json", 0.15, 0.2},
                  {"coupled_blocks.json", 0.02, 0.03},
                  {"cantilever.json", 0.05, 0.08},
                  {"cantilever_explicit.json", 0.05, 0.08},
                  {"land_beam.json", 0, 1},
                  {"land_beam_p2.json", 0, 1},
                  {"probe_indentation.json", 0.5, 0.6},
                  {"slab_ep_0.5mm.json", 0.002, 0.004},
                  {"slab_ep_grid_0.5mm.json", 0.002, 0.004},
                  {"circulation_closed_loop.json", 0.4, 0.9},
                  {"heart.json", 0.1, 0.13},
                  {"heart_mass_spring.json", 0.1, 0.13},
                  {"heart_mixed.json", 0.02, 0.035},
                  {"liver_palpation.json", 1.25, 1.3}};

TEST(Restep, FromOneSnapshotEveryBuiltInTypeIsBitwise) {
  for (const auto& c : kEveryType) {
    SCOPED_TRACE(c.scene);
    ExpectSnapshotRestepIsBitwise(c.scene, c.t1, c.t2);
  }
}

/// The objects and connectors of `coordinator` (and of its aggregates, with their own state)
/// whose snapshots serialise instead of copying a state value, as "name (type)".
void CollectSerialised(const Coordinator& coordinator, std::vector<std::string>& out) {
  for (std::size_t i = 0; i < coordinator.num_objects(); ++i) {
    const SimObject& object = coordinator.object(i);
    if (const auto* aggregate = dynamic_cast<const AggregateObject*>(&object))
      CollectSerialised(aggregate->parts(), out);
    else if (!object.state_is_value())
      out.push_back(fmt::format("{} ({})", object.name(), object.type_name()));
  }
  for (std::size_t i = 0; i < coordinator.num_connectors(); ++i)
    if (!coordinator.connector(i).state_is_value())
      out.push_back(fmt::format("{} ({})", coordinator.connector(i).name(),
                                coordinator.connector(i).type_name()));
}

// Issue 18: a step retry copies values, never serialises, for every built-in type (the haptic
// pair gathers its value from the probe's device, tick and safety stage and the bridge's
// buffers). Aggregates count only if all their parts do.
TEST(Restep, EveryBuiltInTypeKeepsItsStateAsAValue) {
  for (const auto& c : kEveryType) {
    SCOPED_TRACE(c.scene);
    TypeRegistry registry;
    RegisterBuiltins(registry);
    const Scene loaded = LoadScene(std::string(GIPSI_SOURCE_DIR) + "/scenes/" + c.scene, registry);
    std::vector<std::string> serialised;
    CollectSerialised(loaded.kernel->coordinator(), serialised);
    EXPECT_EQ(fmt::format("{}", fmt::join(serialised, ", ")), "");
    const Coordinator& top = loaded.kernel->coordinator();
    for (std::size_t i = 0; i < top.num_objects(); ++i) {
      if (dynamic_cast<const AggregateObject*>(&top.object(i)) != nullptr) {
        EXPECT_TRUE(top.object(i).state_is_value()) << top.object(i).name();
      }
    }
  }
}

TEST(Restep, MassSpringAcrossAnEventIsBitwise) {
  // The corner is released at 1.5 s, between t1 and t2.
  ExpectRestepIsBitwise("hanging_sheet.json", 1.0, 1.6);
}

TEST(Restep, MassSpringContactWithFrictionIsBitwise) {
  // Two blocks, the upper falls on the lower and slides on it (penalty contact with friction):
  // the contact and its friction anchors carry across the restore.
  ExpectRestepIsBitwise("block_drop.json", 0.15, 0.2);
}

TEST(Restep, AggregateWithBoundaryCouplingIsBitwise) {
  ExpectRestepIsBitwise("coupled_blocks.json", 0.02, 0.03);
}

TEST(Restep, FemSolidDynamicIsBitwise) { ExpectRestepIsBitwise("cantilever.json", 0.05, 0.08); }

TEST(Restep, FemSolidThroughTheOdeContractIsBitwise) {
  // RK4 steps the solid (fem_solid_ode.cc): its [u; v] is packed from the state every step.
  ExpectRestepIsBitwise("cantilever_explicit.json", 0.05, 0.08);
}

TEST(Restep, FemSolidQuasiStaticNewtonIsBitwise) {
  // The Land et al. Guccione beam (Static, 10 load steps, Newton with the natural monotonicity
  // test): one macro step, run again from the start after the first run left its warm start,
  // kept factorisation and statistics at the loaded state.
  ExpectRestepIsBitwise("land_beam.json", 0, 1);
}

TEST(Restep, MixedSolidIncompressibleIsBitwise) {
  // The same beam fully incompressible on P2–P1 tets (UMFPACK, exact follower tangent).
  ExpectRestepIsBitwise("land_beam_p2.json", 0, 1);
}

TEST(Restep, FemSolidUnderARigidToolIsBitwise) {
  // FemSolid, a RigidTool on its scripted path and the contact between them.
  ExpectRestepIsBitwise("probe_indentation.json", 0.5, 0.6);
}

TEST(Restep, MonodomainOnTetsIsBitwise) {
  ExpectRestepIsBitwise("slab_ep_0.5mm.json", 0.002, 0.004);
}

TEST(Restep, GridMonodomainIsBitwise) {
  ExpectRestepIsBitwise("slab_ep_grid_0.5mm.json", 0.002, 0.004);
}

TEST(Restep, CirculationAcrossValveEventsIsBitwise) {
  ExpectRestepIsBitwise("circulation_closed_loop.json", 0.4, 0.9);
}

TEST(Restep, HeartIsBitwise) {
  // Monodomain, FEM wall with its kept factorisation, cavity coupling, closed-loop blood and
  // beat monitor: restored in the first contraction.
  ExpectRestepIsBitwise("heart.json", 0.1, 0.13);
}

TEST(Restep, MassSpringHeartIsBitwise) {
  ExpectRestepIsBitwise("heart_mass_spring.json", 0.1, 0.13);
}

TEST(Restep, MixedHeartIsBitwise) {
  // The incompressible P2-P1 wall with its cavity pressure solved as a bordered unknown.
  ExpectRestepIsBitwise("heart_mixed.json", 0.02, 0.035);
}

TEST(Restep, HapticPalpationIsBitwise) {
  // HapticProbe at 1 kHz, HapticCoupling publishing local models, FEM liver: restored while
  // the probe presses (contact from about 1.18 s).
  ExpectRestepIsBitwise("liver_palpation.json", 1.25, 1.3);
}

}  // namespace
}  // namespace gipsi
