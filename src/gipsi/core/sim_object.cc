#include "gipsi/core/sim_object.h"

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/json_node.h"

namespace gipsi {

std::string_view ToString(FieldLocation location) {
  switch (location) {
    case FieldLocation::kNode:
      return "node";
    case FieldLocation::kElement:
      return "element";
    case FieldLocation::kBoundaryVertex:
      return "boundary vertex";
    case FieldLocation::kBoundaryFace:
      return "boundary face";
    case FieldLocation::kGlobal:
      return "global";
  }
  return "?";
}

Index NumDomainElements(const Mesh& mesh) {
  return mesh.num_tets() > 0 ? mesh.num_tets() : mesh.num_triangles();
}

SimObject::SimObject(std::string name)
    : name_(std::move(name)),
      path_(ScopedObjectPath(name_)),
      domain_(std::make_shared<const Mesh>()) {}

void SimObject::SetGeometry(std::shared_ptr<const Mesh> domain, BoundarySurface boundary) {
  GIPSI_CHECK(domain != nullptr);
  domain_ = std::move(domain);
  boundary_ = std::move(boundary);
  bcs_ = BoundaryConditions(boundary_.num_vertices(), boundary_.num_triangles());
  display_ = DisplayGeometry{};
  display_.triangles = boundary_.triangles;
  display_.positions.resize(3, boundary_.num_vertices());
}

PointMap SimObject::MapFromNodes(const Points& targets) const {
  const Mesh& mesh = *domain_;
  return mesh.num_tets() > 0
             ? PointMap::BarycentricInTets(mesh.nodes, mesh.tets, targets)
             : PointMap::BarycentricOnTriangles(mesh.nodes, mesh.triangles, targets);
}

void SimObject::EmbedDisplay(const Points& rest_vertices, const Triangles& triangles,
                             double max_distance) {
  PointMap map = MapFromNodes(rest_vertices);
  if (map.max_distance() > max_distance) {
    ThrowInputError("", fmt::format("objects.{}.display", name_),
                    fmt::format("the display surface lies up to {:.4g} away from the domain "
                                "(allowed {:.4g}); is it in the same units and place?",
                                map.max_distance(), max_distance));
  }
  display_.triangles = triangles;
  display_.map = std::move(map);
  display_.positions = rest_vertices;
  OnDisplayChanged();
}

void SimObject::SetDisplayGeometry(Triangles triangles, PointMap map, Points rest_positions) {
  GIPSI_CHECK(map.num_targets() == rest_positions.cols());
  display_.triangles = std::move(triangles);
  display_.map = std::move(map);
  display_.positions = std::move(rest_positions);
  OnDisplayChanged();
}

void SimObject::UpdateDisplay() const {
  const Points& x = domain_positions();
  if (display_.map) {
    display_.map->Apply(x, display_.positions);
  } else {
    boundary_.Gather(x, display_.positions);
  }
  CorrectDisplayPositions(display_);
}

FieldId SimObject::DeclareField(FieldInfo info) {
  GIPSI_CHECK(!TryFindField(info.name).has_value(), "field '{}' declared twice", info.name);
  GIPSI_CHECK(info.components == 1 || info.components == 3 || info.components == 9);
  fields_.push_back(std::move(info));
  return FieldId(static_cast<std::int64_t>(fields_.size() - 1));
}

MechanicalFieldIds SimObject::DeclareMechanicalFields() {
  using L = FieldLocation;
  using A = FieldAccess;
  MechanicalFieldIds ids;
  ids.position =
      DeclareField({"position", L::kNode, 3, "m", A::kReadWrite, "current node position"});
  ids.velocity = DeclareField({"velocity", L::kNode, 3, "m/s", A::kReadWrite, "node velocity"});
  ids.displacement =
      DeclareField({"displacement", L::kNode, 3, "m", A::kRead, "position minus rest position"});
  ids.external_force = DeclareField({"external_force", L::kNode, 3, "N", A::kReadWrite,
                                     "extra nodal force (volume coupling input)"});
  ids.boundary_position = DeclareField({"boundary_position", L::kBoundaryVertex, 3, "m", A::kRead,
                                        "current boundary vertex position"});
  ids.boundary_velocity = DeclareField(
      {"boundary_velocity", L::kBoundaryVertex, 3, "m/s", A::kRead, "boundary vertex velocity"});
  ids.boundary_displacement = DeclareField({"boundary_displacement", L::kBoundaryVertex, 3, "m",
                                            A::kRead, "boundary vertex displacement"});
  ids.reaction_force =
      DeclareField({"reaction_force", L::kBoundaryVertex, 3, "N", A::kRead,
                    "force the kinematic constraints exert on constrained boundary vertices"});
  return ids;
}

bool SimObject::ReadBoundaryKinematics(const MechanicalFieldIds& ids, FieldId id,
                                       const Points& positions, const double* velocities,
                                       Eigen::Ref<Eigen::MatrixXd> out) const {
  if (id != ids.boundary_position && id != ids.boundary_velocity && id != ids.boundary_displacement)
    return false;
  const auto& v2n = boundary_.vertex_to_node;
  for (std::size_t j = 0; j < v2n.size(); ++j) {
    const Index node = v2n[j];
    const auto col = static_cast<Index>(j);
    if (id == ids.boundary_position) out.col(col) = positions.col(node);
    if (id == ids.boundary_velocity) out.col(col) = Eigen::Map<const Vec3>(velocities + 3 * node);
    if (id == ids.boundary_displacement)
      out.col(col) = positions.col(node) - domain_->nodes.col(node);
  }
  return true;
}

std::optional<FieldId> SimObject::TryFindField(std::string_view name) const {
  for (std::size_t i = 0; i < fields_.size(); ++i)
    if (fields_[i].name == name) return FieldId(static_cast<std::int64_t>(i));
  return std::nullopt;
}

FieldId SimObject::FindField(std::string_view name) const {
  if (auto id = TryFindField(name)) return *id;
  std::vector<std::string> names;
  std::string list;
  for (const auto& f : fields_) {
    names.push_back(f.name);
    list += (list.empty() ? "" : ", ") + f.name;
  }
  throw InputError(fmt::format("object '{}' ({}) has no field '{}'{}; its fields are: {}", name_,
                               type_name(), name, SuggestClosest(name, names), list));
}

const FieldInfo& SimObject::field_info(FieldId id) const {
  GIPSI_CHECK(id.is_valid() && id.value() < static_cast<std::int64_t>(fields_.size()),
              "invalid field id {} for object '{}'", id.value(), name_);
  return fields_[static_cast<std::size_t>(id.value())];
}

Index SimObject::FieldCount(FieldId id) const {
  switch (field_info(id).location) {
    case FieldLocation::kNode:
      return domain_->num_nodes();
    case FieldLocation::kElement:
      return NumDomainElements(*domain_);
    case FieldLocation::kBoundaryVertex:
      return boundary_.num_vertices();
    case FieldLocation::kBoundaryFace:
      return boundary_.num_triangles();
    case FieldLocation::kGlobal:
      return 1;
  }
  return 0;
}

void SimObject::ReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  const FieldInfo& info = field_info(id);
  GIPSI_CHECK(info.readable(), "field '{}' of '{}' is write-only", info.name, name_);
  GIPSI_CHECK(out.rows() == info.components && out.cols() == FieldCount(id),
              "field '{}' of '{}' is {} by {}, buffer is {} by {}", info.name, name_,
              info.components, FieldCount(id), out.rows(), out.cols());
  DoReadField(id, out);
}

void SimObject::ReadFieldItems(FieldId id, std::span<const int> items,
                               Eigen::Ref<Eigen::MatrixXd> out) const {
  const FieldInfo& info = field_info(id);
  GIPSI_CHECK(info.readable(), "field '{}' of '{}' is write-only", info.name, name_);
  GIPSI_CHECK(info.location != FieldLocation::kGlobal, "field '{}' of '{}' has no items", info.name,
              name_);
  GIPSI_CHECK(out.rows() == info.components && out.cols() == static_cast<Index>(items.size()),
              "field '{}' of '{}': {} items of {} components, buffer is {} by {}", info.name, name_,
              items.size(), info.components, out.rows(), out.cols());
  const Index count = FieldCount(id);
  for (const int i : items)
    GIPSI_CHECK(i >= 0 && i < count, "field '{}' of '{}' has {} items, asked for item {}",
                info.name, name_, count, i);
  DoReadFieldItems(id, items, out);
}

void SimObject::DoReadFieldItems(FieldId id, std::span<const int> items,
                                 Eigen::Ref<Eigen::MatrixXd> out) const {
  const FieldInfo& info = field_info(id);
  const Index count = FieldCount(id);
  Eigen::MatrixXd whole;
  const double* values = DoFieldMemory(id);
  if (values == nullptr) {
    whole.resize(info.components, count);
    DoReadField(id, whole);
    values = whole.data();
  }
  const Eigen::Map<const Eigen::MatrixXd> all(values, info.components, count);
  for (std::size_t k = 0; k < items.size(); ++k) out.col(static_cast<Index>(k)) = all.col(items[k]);
}

const double* SimObject::FieldMemory(FieldId id) const {
  return field_info(id).readable() ? DoFieldMemory(id) : nullptr;
}

void SimObject::WriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) {
  const FieldInfo& info = field_info(id);
  GIPSI_CHECK(info.writable(), "field '{}' of '{}' is read-only", info.name, name_);
  GIPSI_CHECK(in.rows() == info.components && in.cols() == FieldCount(id),
              "field '{}' of '{}' is {} by {}, data is {} by {}", info.name, name_, info.components,
              FieldCount(id), in.rows(), in.cols());
  DoWriteField(id, in);
}

StepStatus SimObject::Step(double dt) {
  if (!(dt > 0)) return StepStatus::Failed("time step is not positive", -1, dt);
  StepStatus status = DoStep(time_, dt);
  if (status.ok()) {
    ++step_count_;
    time_ += dt;
  }
  return status;
}

}  // namespace gipsi
