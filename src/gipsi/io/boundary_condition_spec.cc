#include "gipsi/io/boundary_condition_spec.h"

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/geometry/region_json.h"

namespace gipsi {
namespace {

AxisMask ParseAxes(const JsonNode& node) {
  if (node.raw().is_boolean()) {
    if (!node.AsBool()) node.Expected("true or a list of axes");
    return kAllAxes;
  }
  AxisMask mask = 0;
  for (const auto& item : node.Items()) {
    std::string axis = item.AsChoice({"x", "y", "z"});
    mask |= static_cast<AxisMask>(1 << (axis[0] - 'x'));
  }
  if (mask == 0) node.Expected("at least one axis");
  return mask;
}

}  // namespace

BoundaryConditionSpec ParseBoundaryCondition(const JsonNode& node, const SimObject& object,
                                             std::size_t index) {
  using Kind = BoundaryConditionSpec::Kind;
  node.CheckKeys({"name", "region", "fix", "displacement", "velocity", "axes", "force",
                  "total_force", "pressure", "traction", "description"});
  BoundaryConditionSpec spec;
  spec.name = node.String("name", fmt::format("#{}", index));
  spec.path = node.path();
  int kinds = 0;
  for (const char* key :
       {"fix", "displacement", "velocity", "force", "total_force", "pressure", "traction"})
    kinds += node.Has(key) ? 1 : 0;
  if (kinds != 1)
    node.Fail(
        "expected exactly one of 'fix', 'displacement', 'velocity', 'force', "
        "'total_force', 'pressure', 'traction'");
  Region region = AllRegion{};
  if (auto r = node.Find("region")) region = ParseRegion(*r);
  // An object split over the processes without its whole mesh keeps its part's conditions; how
  // many items the whole selection has only its collective calls know (every process parses
  // alike).
  const auto* split = dynamic_cast<const PartitionedObject*>(&object);
  if (split != nullptr && split->holds_whole_domain()) split = nullptr;
  if (split == nullptr && object.boundary().num_vertices() == 0)
    node.Fail(
        fmt::format("object '{}' has no boundary geometry to put conditions on", object.path()));

  bool on_faces = node.Has("pressure") || node.Has("traction");
  std::int64_t whole_count = 0;
  try {
    if (split != nullptr) {
      PartitionedObject::ConditionItems selected = split->SelectConditionItems(region, on_faces);
      (on_faces ? spec.faces : spec.vertices) = std::move(selected.items);
      whole_count = selected.whole_count;
    } else {
      if (on_faces)
        spec.faces = SelectBoundaryFaces(region, object.domain(), object.boundary());
      else
        spec.vertices = SelectBoundaryVertices(region, object.domain(), object.boundary());
      whole_count = static_cast<std::int64_t>(spec.faces.size() + spec.vertices.size());
    }
  } catch (const InputError& e) {
    node.At("region").Fail(e.what());
  }
  if (whole_count == 0)
    node.Fail(fmt::format("the region selects no boundary {} of object '{}'",
                          on_faces ? "triangle" : "vertex", object.path()));
  if (node.Has("axes") && !node.Has("displacement") && !node.Has("velocity"))
    node.At("axes").Fail("'axes' applies to 'displacement' and 'velocity' only");

  if (auto fix = node.Find("fix")) {
    spec.kind = Kind::kFix;
    spec.axes = ParseAxes(*fix);
  } else if (auto u = node.Find("displacement")) {
    spec.kind = Kind::kDisplacement;
    spec.vector = u->AsVec3();
    if (auto axes = node.Find("axes")) spec.axes = ParseAxes(*axes);
  } else if (auto v = node.Find("velocity")) {
    spec.kind = Kind::kVelocity;
    spec.vector = v->AsVec3();
    if (auto axes = node.Find("axes")) spec.axes = ParseAxes(*axes);
  } else if (auto f = node.Find("force")) {
    spec.kind = Kind::kForce;
    spec.vector = f->AsVec3();
  } else if (auto total = node.Find("total_force")) {
    spec.kind = Kind::kForce;
    spec.vector = total->AsVec3() / static_cast<double>(whole_count);
  } else if (auto p = node.Find("pressure")) {
    spec.kind = Kind::kPressure;
    spec.scalar = p->AsNumber();
  } else {
    spec.kind = Kind::kTraction;
    spec.vector = node.At("traction").AsVec3();
  }
  return spec;
}

void BoundaryConditionSpec::Apply(BoundaryConditions& bcs) const {
  switch (kind) {
    case Kind::kFix:
      for (int v : vertices) bcs.Fix(v, axes);
      break;
    case Kind::kDisplacement:
      for (int v : vertices) bcs.PrescribeDisplacement(v, vector, axes);
      break;
    case Kind::kVelocity:
      for (int v : vertices) bcs.PrescribeVelocity(v, vector, axes);
      break;
    case Kind::kForce:
      for (int v : vertices) bcs.SetForce(v, vector);
      break;
    case Kind::kPressure:
      for (int f : faces) bcs.SetPressure(f, scalar);
      break;
    case Kind::kTraction:
      for (int f : faces) bcs.SetTraction(f, vector);
      break;
  }
}

void BoundaryConditionSpec::Remove(BoundaryConditions& bcs) const {
  switch (kind) {
    case Kind::kFix:
    case Kind::kDisplacement:
    case Kind::kVelocity:
      for (int v : vertices) bcs.Release(v, axes);
      break;
    case Kind::kForce:
      for (int v : vertices) bcs.SetForce(v, Vec3::Zero());
      break;
    case Kind::kPressure:
      for (int f : faces) bcs.SetPressure(f, 0);
      break;
    case Kind::kTraction:
      for (int f : faces) bcs.SetTraction(f, Vec3::Zero());
      break;
  }
}

}  // namespace gipsi
