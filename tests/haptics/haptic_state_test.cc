// Checkpoints of the haptic path (haptic_state.cc): a tick and its bridge restored in the middle
// of a model continue bit for bit, and a lock-free buffer's layout is restored whole or not at
// all. The end-to-end case (the palpation demo resumed through the command line) is
// Resume.HapticPalpationIsBitwiseIdentical in tests/core/checkpoint_test.cc.

#include <gtest/gtest.h>

#include <string>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/base/state_value.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/haptics/haptic_bridge.h"
#include "gipsi/haptics/virtual_device.h"
#include "gipsi/models/fem/fem_local_model.h"
#include "models/fem/fem_test_util.h"

namespace gipsi {
namespace {

using testing::AccurateParams;
using testing::VerticesWhere;

/// A 4 × 4 × 2 cm neo-Hookean block on a fixed base (z = 0); top surface at z = 0.02.
std::unique_ptr<FemSolid> Block() {
  auto mesh = std::make_shared<const Mesh>(
      MakeTetBox(Vec3(-0.02, -0.02, 0), Vec3(0.02, 0.02, 0.02), {6, 6, 3}));
  auto fem = std::make_unique<FemSolid>(
      "block", mesh,
      AccurateParams(R"({"law": "NeoHookean", "youngs_modulus": 1e4, "poisson_ratio": 0.45})",
                     ImplicitSchemeKind::kStatic));
  for (Index j : VerticesWhere(*fem, [](const Vec3& X) { return X.z() == 0; }))
    fem->boundary_conditions().Fix(j);
  return fem;
}

/// The device starts 0.1 mm into the top centre and presses 1 mm deeper over 0.1 s.
std::vector<DeviceKeyframe> Press() {
  return {{0.0, Vec3(0, 0, 0.0199), 0}, {0.1, Vec3(0, 0, 0.0189), 0}};
}

/// One side of the comparison: a device, a bridge and a tick on the bridge's buffers.
struct HapticSide {
  explicit HapticSide(LocalModelBuilder& builder) : device(Press()), bridge(builder, {}) {
    LocalTickParams params;
    params.blend_time = 0.05;  // the hand-over blend is still running at the checkpoint
    params.safety.max_rate = 1e6;
    tick = std::make_unique<LocalModelTick>(device, DeviceWorkspace{}, bridge.models(),
                                            &bridge.feedback(), params);
  }
  VirtualDevice device;
  HapticBridge bridge;
  std::unique_ptr<LocalModelTick> tick;
};

TEST(HapticState, ATickRestoredInTheMiddleOfAModelContinuesBitwise) {
  auto fem = Block();
  FemCondensation builder(*fem);
  const double h = 1e-3;
  HapticSide a(builder);
  a.bridge.SeedTool(Vec3(0, 0, 0.0199));
  a.bridge.Publish(0);
  // 30 ticks into the model: the local state has moved away from its anchor, the blend offset
  // is fading and the depth history is set; no new model waits in the buffer.
  for (int k = 1; k <= 30; ++k) a.tick->Run(k * h, h);
  ASSERT_GT(a.tick->model_force(), 0);
  ASSERT_GT(a.tick->state().v.norm(), 0);
  // The three state values, through the generic checkpoint format.
  HapticBridgeState bridge;
  LocalTickState tick;
  a.bridge.GetState(bridge);
  a.tick->GetState(tick);
  StateWriter out;
  WriteFields(out, a.device.state());
  WriteFields(out, bridge);
  WriteFields(out, tick);

  HapticSide b(builder);  // a fresh side, as in a new process
  StateReader in(out.TakeBytes(), "the test's state");
  VirtualDeviceState read_device;
  HapticBridgeState read_bridge;
  LocalTickState read_tick;
  ReadFields(in, read_device);
  ReadFields(in, read_bridge);
  ReadFields(in, read_tick);
  ASSERT_TRUE(in.at_end());
  b.device.set_state(read_device);
  b.bridge.SetState(read_bridge);
  b.tick->SetState(read_tick);
  for (int k = 31; k <= 120; ++k) {
    if (k == 60) {  // a hand-over after the restore: the same model is built for both
      a.bridge.ApplyFeedback();
      b.bridge.ApplyFeedback();
      a.bridge.Publish(k * h);
      b.bridge.Publish(k * h);
    }
    const Vec3 fa = a.tick->Run(k * h, h);
    const Vec3 fb = b.tick->Run(k * h, h);
    // Bitwise: the same operations on the same bits.
    ASSERT_EQ(fa, fb) << "tick " << k;
    ASSERT_EQ(a.tick->proxy(), b.tick->proxy()) << "tick " << k;
    ASSERT_EQ(a.tick->state().u, b.tick->state().u) << "tick " << k;
  }
  EXPECT_EQ(a.tick->num_handovers(), 2);
  EXPECT_EQ(b.tick->num_handovers(), 2);
  EXPECT_EQ(a.device.num_commands(), b.device.num_commands());
}

TEST(HapticState, ABridgeRefusesAStateThatDoesNotFitItAndKeepsItsOwn) {
  auto fem = Block();
  FemCondensation builder(*fem);
  HapticSide side(builder);
  side.bridge.SeedTool(Vec3(0, 0, 0.0199));
  side.bridge.Publish(0);
  HapticBridgeState good;
  side.bridge.GetState(good);
  ASSERT_GE(good.contact, 0);
  const auto expect_refused = [&](const HapticBridgeState& bad, const std::string& why) {
    try {
      side.bridge.SetState(bad);
      ADD_FAILURE() << "accepted: " << why;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    HapticBridgeState now;
    side.bridge.GetState(now);
    EXPECT_EQ(FirstDifference(good, now), "");
  };
  HapticBridgeState bad = good;
  bad.models.roles = {0, 0, 2};  // two sides on one slot
  expect_refused(bad, "the local model buffer's layout is corrupted");
  bad = good;
  bad.contact = fem->boundary().num_vertices();
  expect_refused(bad, "the state was written for another scene");
  bad = good;
  bad.models.slots[1].num_nodes += 1;  // arrays sized for another model
  expect_refused(bad, "has arrays of other sizes");
}

TEST(HapticState, ABufferLayoutIsRestoredWholeOrNotAtAll) {
  LatestValue<int> buffer(0);
  buffer.back() = 7;
  buffer.Publish();  // 7 waits for the consumer
  const auto saved = buffer.layout();
  EXPECT_TRUE(saved.fresh);

  LatestValue<int> copy(0);
  for (int i = 0; i < 3; ++i) copy.slot(i) = buffer.slot(i);
  ASSERT_TRUE(copy.set_layout(saved));
  ASSERT_TRUE(copy.Fetch());  // the unfetched value is handed over after the restore
  EXPECT_EQ(copy.front(), 7);
  EXPECT_FALSE(copy.Fetch());

  // Two sides on one slot would let the producer write what the consumer reads.
  auto bad = saved;
  bad.front = bad.back;
  const auto before = buffer.layout();
  EXPECT_FALSE(buffer.set_layout(bad));
  EXPECT_EQ(buffer.layout().back, before.back);
  EXPECT_EQ(buffer.layout().middle, before.middle);
  EXPECT_EQ(buffer.layout().front, before.front);
  EXPECT_TRUE(buffer.layout().fresh);
  bad = saved;
  bad.middle = 3;
  EXPECT_FALSE(buffer.set_layout(bad));
}

}  // namespace
}  // namespace gipsi
