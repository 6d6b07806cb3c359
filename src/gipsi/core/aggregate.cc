#include "gipsi/core/aggregate.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <string>

#include "gipsi/base/units.h"

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/core/in_blocks.h"

namespace gipsi {

AggregateObject::AggregateObject(std::string name, Coordinator parts)
    : SimObject(std::move(name)), parts_(std::move(parts)) {
  static NoState nothing;                // has no fields: never read or written
  own_state_ = BindStateValue(nothing);  // until a subclass binds its own
  for (std::size_t i = 0; i < parts_.num_objects(); ++i) {
    SimObject& part = parts_.object(i);
    for (std::size_t f = 0; f < part.fields().size(); ++f) {
      FieldInfo info = part.fields()[f];
      // Only global fields keep their meaning without the part's geometry in this object;
      // the others are still reachable through the part itself ("heart.muscle").
      if (info.location != FieldLocation::kGlobal) continue;
      info.name = part.name() + "." + info.name;
      DeclareField(info);
      proxies_.push_back({&part, FieldId(static_cast<std::int64_t>(f))});
    }
  }
}

void AggregateObject::CollectLeaves(std::vector<const SimObject*>& out) const {
  for (std::size_t i = 0; i < parts_.num_objects(); ++i) parts_.object(i).CollectLeaves(out);
}

SimObject* AggregateObject::FindPart(std::string_view name) const {
  return parts_.FindObject(name);
}

StepStatus AggregateObject::DoStep(double t, double dt) {
  // A kernel retrying a failed macro step asks for a fraction of the aggregate's step.
  const int split = std::max(1, static_cast<int>(std::lround(parts_.macro_dt() / dt)));
  if (auto failure = parts_.MacroStep(t, step_count(), split)) {
    const std::string& inner = failure->detail;
    failure_detail_ = std::string(failure->is_connector ? "connector '" : "part '") +
                      std::string(failure->who) + "'" + (inner.empty() ? "" : ", " + inner);
    return failure->status;
  }
  return StepStatus::Ok();
}

std::vector<SimObject::ProfileEntry> AggregateObject::ProfileBreakdown() const {
  std::vector<ProfileEntry> entries;
  for (std::size_t i = 0; i < parts_.num_objects(); ++i)
    entries.push_back({"part " + parts_.object(i).name(), parts_.object_seconds(i), "s"});
  for (std::size_t i = 0; i < parts_.num_connectors(); ++i)
    entries.push_back(
        {"connector " + parts_.connector(i).name(), parts_.connector_seconds(i), "s"});
  for (std::size_t i = 0; i < parts_.num_objects(); ++i)
    for (ProfileEntry& e : parts_.object(i).ProfileBreakdown())
      entries.push_back({parts_.object(i).name() + ": " + e.name, e.value, e.unit});
  return entries;
}

void AggregateObject::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  const Proxy& p = proxies_[static_cast<std::size_t>(id.value())];
  p.part->ReadField(p.field, out);
}

void AggregateObject::DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) {
  const Proxy& p = proxies_[static_cast<std::size_t>(id.value())];
  p.part->WriteField(p.field, in);
}

Coordinator BuildAggregateParts(const ObjectBuildContext& ctx, const JsonNode& p) {
  // Parts and connectors built here are called "<aggregate>.<name>" in messages.
  const ObjectPathScope scope(ScopedObjectPath(ctx.name));
  Coordinator parts;
  JsonNode part_nodes = p.At("parts");
  if (part_nodes.size() == 0) part_nodes.Expected("at least one part");
  // Made in blocks (its parts too, by the scene's rule among them) only when nothing outside
  // reads its parts.
  const std::set<std::string> in_blocks =
      ctx.in_blocks ? InBlocksObjects(part_nodes, p.Find("connectors"), ctx.registry)
                    : std::set<std::string>{};
  for (const auto& [name, node] : part_nodes.Members()) {
    BuiltObject built = ctx.build_object(name, node, in_blocks.count(name) > 0);
    try {
      parts.AddObject(std::move(built.object), built.dt);
    } catch (const InputError& e) {
      node.Fail(e.what());
    }
  }
  if (auto connectors = p.Find("connectors")) {
    for (const auto& [name, node] : connectors->Members()) {
      auto connector = ctx.registry.CreateConnector(name, node, parts);
      parts.AddConnector(std::move(connector), static_cast<int>(node.Int("every", 1)));
    }
  }
  if (auto order = p.Find("order")) parts.SetOrder(order->AsStrings(), order->path());
  JsonNode dt = p.At("dt");
  try {
    parts.Prepare(ReadPositiveQuantity(dt, "s"));
  } catch (const WiringError& e) {
    if (e.order_path().empty()) p.At("connectors").At(e.connector()).Fail(e.what());
    p.At("order").Fail(e.what());
  } catch (const InputError& e) {
    dt.Fail(e.what());
  }
  return parts;
}

void RegisterAggregate(TypeRegistry& registry) {
  registry.objects.Register(
      "Aggregate",
      [](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        ctx.CheckKeys({"parts", "connectors", "order"});
        return std::make_unique<AggregateObject>(ctx.name, BuildAggregateParts(ctx, ctx.params));
      },
      "an object made of parts and the connectors between them");
}

}  // namespace gipsi
