// Connector ports and order rules, checked by Coordinator::Prepare (gipsi/core/port.h).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>

#include "gipsi/core/aggregate.h"
#include "gipsi/core/coordinator.h"
#include "test_objects.h"

namespace gipsi {
namespace {

using testing::CountingObject;
using ::testing::HasSubstr;

/// A connector that declares whatever the test asks and transfers nothing.
class Wired final : public Connector {
 public:
  Wired(std::string name, const std::function<void(Wired&)>& declare) : Connector(std::move(name)) {
    declare(*this);
  }
  using Connector::RequireOrder;
  using Connector::UseBoundaryConditions;
  using Connector::UseCapability;
  using Connector::UseField;
  [[nodiscard]] std::string_view type_name() const override { return "Wired"; }

 protected:
  StepStatus DoFire(double /*t*/) override { return StepStatus::Ok(); }
};

/// Two Counting objects "a" and "b" (fields "value": 3 components [1] read/write, "clock":
/// 1 component [s] read-only) and a connector "c" declaring `declare`.
struct Scene {
  Coordinator coordinator;
  SimObject* a = nullptr;
  SimObject* b = nullptr;
  Scene(const std::function<void(Wired&, SimObject&, SimObject&)>& declare, double dt_b = 1e-3,
        int every = 1) {
    a = &coordinator.AddObject(std::make_unique<CountingObject>("a"), 1e-3);
    b = &coordinator.AddObject(std::make_unique<CountingObject>("b"), dt_b);
    coordinator.AddConnector(std::make_unique<Wired>("c", [&](Wired& w) { declare(w, *a, *b); }),
                             every);
  }
};

// The message of the WiringError that Prepare throws, or "no error".
std::string PrepareError(Coordinator& coordinator, std::string* order_path = nullptr) {
  try {
    coordinator.Prepare(1e-3);
  } catch (const WiringError& e) {
    EXPECT_EQ(e.connector(), "c");
    if (order_path) *order_path = e.order_path();
    return e.what();
  }
  return "no error";
}

TEST(Wiring, PortsThatMatchTheFieldsPass) {
  Scene s([](Wired& w, SimObject& a, SimObject& b) {
    w.UseField("from", a, "clock", FieldAccess::kRead, "s", 1);
    w.UseField("to", b, "value", FieldAccess::kReadWrite, "1", 3);
    w.UseBoundaryConditions("to", b);
    w.UseCapability("from", a, "counter");
  });
  EXPECT_EQ(PrepareError(s.coordinator), "no error");
  const Connector& c = s.coordinator.connector(0);
  ASSERT_EQ(c.ports().size(), 4u);
  EXPECT_EQ(DescribePort(c.ports()[0]), "reads a.clock [s] (from)");
  EXPECT_EQ(DescribePort(c.ports()[1]), "reads and writes b.value [1] (to)");
  EXPECT_EQ(DescribePort(c.ports()[2]), "sets the boundary conditions of b (to)");
  EXPECT_EQ(DescribePort(c.ports()[3]), "calls a as counter (from)");
}

TEST(Wiring, AFieldPortThatDoesNotMatchNamesBothEnds) {
  auto error = [](const std::function<void(Wired&, SimObject&)>& declare) {
    Scene s([&](Wired& w, SimObject& a, SimObject&) { declare(w, a); });
    return PrepareError(s.coordinator);
  };
  EXPECT_EQ(
      error([](Wired& w, SimObject& a) { w.UseField("from", a, "clok", FieldAccess::kRead); }),
      "connector 'c' (Wired) reads field 'clok' of 'a' (Counting) at its 'from' key, but "
      "that object has no such field (its fields: value, clock)");
  EXPECT_THAT(
      error([](Wired& w, SimObject& a) { w.UseField("to", a, "clock", FieldAccess::kWrite); }),
      HasSubstr("writes field 'clock' of 'a' (Counting) at its 'to' key, but the field cannot be "
                "written (it is read-only)"));
  EXPECT_THAT(error([](Wired& w, SimObject& a) {
                w.UseField("from", a, "value", FieldAccess::kRead, "", 1);
              }),
              HasSubstr("the field has 3 component(s) and the connector works with 1"));
  // Another dimension, and the same dimension at another scale (a connector does not convert).
  EXPECT_THAT(error([](Wired& w, SimObject& a) {
                w.UseField("from", a, "clock", FieldAccess::kRead, "m");
              }),
              HasSubstr("the field is in [s], which does not convert to the connector's [m]"));
  EXPECT_THAT(error([](Wired& w, SimObject& a) {
                w.UseField("from", a, "clock", FieldAccess::kRead, "ms");
              }),
              HasSubstr("the field is in [s] and the connector works in [ms] without converting "
                        "(1 s = 1000 ms)"));
  // Equal units under another spelling convert with factor 1, and pass.
  EXPECT_EQ(error([](Wired& w, SimObject& a) {
              w.UseField("from", a, "clock", FieldAccess::kRead, "second");
            }),
            "no error");
}

TEST(Wiring, OrderRulesAreCheckedAgainstTheScheduleBeforeTheFirstStep) {
  const auto declare = [](Wired& w, SimObject& a, SimObject& b) {
    w.RequireOrder({&a, &b, false, "b needs what a made"});
  };
  {
    // The default order fires every connector first: the rule fails, at the connector.
    Scene s(declare);
    std::string path = "unset";
    EXPECT_EQ(PrepareError(s.coordinator, &path),
              "connector 'c' (Wired) must fire after 'a' steps and before 'b' steps (b needs "
              "what a made), but the default order (every connector, then every object: [c, a, "
              "b]) does not; list them in that order");
    EXPECT_EQ(path, "");
  }
  {
    Scene s(declare);
    s.coordinator.SetOrder({"b", "c", "a"}, "schedule.order");
    std::string path;
    EXPECT_THAT(PrepareError(s.coordinator, &path), HasSubstr("but the order [b, c, a] does not"));
    EXPECT_EQ(path, "schedule.order");
  }
  {
    Scene s(declare);
    s.coordinator.SetOrder({"a", "c", "b"});
    EXPECT_EQ(PrepareError(s.coordinator), "no error");
  }
}

TEST(Wiring, ASameStepRuleNeedsEqualTimeStepsAndEveryMacroStep) {
  const auto declare = [](Wired& w, SimObject& a, SimObject& b) {
    w.RequireOrder({&a, &b, true, "a per-step hand-over"});
  };
  {
    Scene s(declare, 5e-4);
    s.coordinator.SetOrder({"a", "c", "b"});
    EXPECT_THAT(PrepareError(s.coordinator),
                HasSubstr("needs 'a' and 'b' to step with the same time step (a per-step "
                          "hand-over), but they step with 0.001 s and 0.0005 s"));
  }
  {
    Scene s(declare, 1e-3, 2);
    s.coordinator.SetOrder({"a", "c", "b"});
    EXPECT_THAT(PrepareError(s.coordinator),
                HasSubstr("must fire every macro step (a per-step hand-over), but 'every' is 2"));
  }
}

TEST(Wiring, APartOfAnAggregateTakesTheAggregatesPlaceInTheOrder) {
  Coordinator parts;
  SimObject& inner = parts.AddObject(std::make_unique<CountingObject>("inner"), 1e-3);
  parts.Prepare(1e-3);
  Coordinator top;
  top.AddObject(std::make_unique<AggregateObject>("outer", std::move(parts)), 1e-3);
  SimObject& b = top.AddObject(std::make_unique<CountingObject>("b"), 1e-3);
  top.AddConnector(std::make_unique<Wired>("c", [&](Wired& w) {
    w.UseField("from", inner, "clock", FieldAccess::kRead, "s");
    w.RequireOrder({&inner, &b, false, "b needs what inner made"});
  }));
  top.SetOrder({"outer", "c", "b"});
  EXPECT_EQ(PrepareError(top), "no error");
  top.SetOrder({"c", "outer", "b"});
  EXPECT_THAT(PrepareError(top), HasSubstr("must fire after 'inner' steps"));
  // An object the coordinator does not schedule.
  CountingObject stranger("stranger");
  Coordinator lonely;
  lonely.AddObject(std::make_unique<CountingObject>("a"), 1e-3);
  lonely.AddConnector(std::make_unique<Wired>(
      "c", [&](Wired& w) { w.UseField("from", stranger, "clock", FieldAccess::kRead); }));
  EXPECT_EQ(PrepareError(lonely),
            "connector 'c' (Wired) uses object 'stranger' at its 'from' key, which is not among "
            "the objects it is scheduled with");
}

}  // namespace
}  // namespace gipsi
