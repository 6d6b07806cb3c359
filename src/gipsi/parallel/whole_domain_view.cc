/// @file
/// A distributed object's part seen as one object on the whole mesh.

#include "gipsi/parallel/whole_domain_view.h"

#include <fmt/format.h>
#include <petscvec.h>

#include <algorithm>
#include <array>
#include <map>
#include <numeric>
#include <span>
#include <variant>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/region.h"
#include "gipsi/models/connectors/item_positions.h"
#include "gipsi/parallel/parts_interpolation.h"
#include "gipsi/parallel/petsc_check.h"

namespace gipsi {

// ShareOwnedNodeValues: shared nodes refreshed from their owners through a ghosted PETSc Vec
// (the part's owned nodes in the global numbering, its shared ones as ghosts).
struct WholeDomainView::NodeExchange {
  std::map<int, Vec> by_components;  // block size → its ghosted Vec
  NodeExchange() = default;
  NodeExchange(const NodeExchange&) = delete;
  NodeExchange& operator=(const NodeExchange&) = delete;
  ~NodeExchange() {
    for (auto& entry : by_components) VecDestroy(&entry.second);
  }
};

WholeDomainView::~WholeDomainView() = default;

std::unique_ptr<PartsInterpolation> WholeDomainView::InterpolateAtPoints(
    const Points& points) const {
  return MakePartsInterpolation(
      *part_, mesh_part_, points, comm_,
      [this](FieldId id) { return part_field_[static_cast<std::size_t>(id.value())]; },
      [this](Eigen::Ref<Eigen::MatrixXd> values) { ShareOwnedNodeValues(values); });
}

std::unique_ptr<PartsInterpolation> WholeDomainView::NearestAtPoints(FieldLocation location,
                                                                     const Points& points) const {
  const bool boundary =
      location == FieldLocation::kBoundaryVertex || location == FieldLocation::kBoundaryFace;
  if (location == FieldLocation::kGlobal || (boundary && !part_only_))
    throw InputError(fmt::format("'{}': no nearest item of a {} field across the parts", name(),
                                 location == FieldLocation::kGlobal ? "global" : "boundary"));
  // Each item of the whole object on one rank: owned nodes and boundary vertices come first in
  // the part's order; tets and boundary faces are all the part's own.
  const Points all = ItemRestPositions(*part_, location);
  const Index count = location == FieldLocation::kNode ? static_cast<Index>(mesh_part_.num_owned)
                      : location == FieldLocation::kBoundaryVertex
                          ? static_cast<Index>(owned_vertices_)
                          : all.cols();
  const std::vector<int>& whole = WholeOfLocal(location);
  GIPSI_CHECK(count <= all.cols(), "'{}': {} nearest candidates of {} items", name(), count,
              all.cols());
  if (static_cast<std::size_t>(count) > whole.size())  // a part-only view without a BoundaryMap
    throw InputError(
        fmt::format("'{}': its part's boundary has no numbers on the whole boundary", name()));
  NearestItems items;
  items.positions = all.leftCols(count);
  for (Index i = 0; i < count; ++i) {
    items.keys.push_back(whole[static_cast<std::size_t>(i)]);
    items.columns.push_back(i);
  }
  return MakePartsNearest(*part_, std::move(items), points, comm_, [this](FieldId id) {
    return part_field_[static_cast<std::size_t>(id.value())];
  });
}

std::unique_ptr<BoundaryInterpolation> WholeDomainView::InterpolateOnBoundary(
    const Points& points) const {
  if (!part_only_)
    throw InputError(fmt::format(
        "'{}' holds its whole mesh on every rank: its boundary fields are whole there", name()));
  return MakePartsOnBoundary(*part_, mesh_part_, points, comm_, [this](FieldId id) {
    return part_field_[static_cast<std::size_t>(id.value())];
  });
}

void WholeDomainView::ShareOwnedNodeValues(Eigen::Ref<Eigen::MatrixXd> values) const {
  const auto n = static_cast<Index>(mesh_part_.whole_node.size());
  const auto owned = static_cast<Index>(mesh_part_.num_owned);
  const auto c = static_cast<int>(values.rows());
  GIPSI_CHECK(values.cols() == n && c >= 1, "'{}': {} by {} values for {} part nodes", name(), c,
              values.cols(), n);
  if (mesh_part_.size == 1) return;  // one rank owns every node: nothing is shared
  if (!exchange_) exchange_ = std::make_unique<NodeExchange>();
  Vec& shared = exchange_->by_components[c];
  if (shared == nullptr) {  // collective: every rank asks for the same component counts
    std::vector<PetscInt> ghosts;
    ghosts.reserve(static_cast<std::size_t>(n - owned));
    for (Index i = owned; i < n; ++i)
      ghosts.push_back(static_cast<PetscInt>(mesh_part_.global[static_cast<std::size_t>(i)]));
    GIPSI_PETSC(VecCreateGhostBlock(comm_, c, static_cast<PetscInt>(c * owned), PETSC_DECIDE,
                                    static_cast<PetscInt>(ghosts.size()), ghosts.data(), &shared));
  }
  // The local form holds the owned nodes' blocks, then the shared ones', as `values` does.
  Vec local = nullptr;
  PetscScalar* a = nullptr;
  GIPSI_PETSC(VecGhostGetLocalForm(shared, &local));
  GIPSI_PETSC(VecGetArray(local, &a));
  for (Index i = 0; i < owned; ++i)
    for (int k = 0; k < c; ++k) a[c * i + k] = values(k, i);
  GIPSI_PETSC(VecRestoreArray(local, &a));
  GIPSI_PETSC(VecGhostRestoreLocalForm(shared, &local));
  GIPSI_PETSC(VecGhostUpdateBegin(shared, INSERT_VALUES, SCATTER_FORWARD));
  GIPSI_PETSC(VecGhostUpdateEnd(shared, INSERT_VALUES, SCATTER_FORWARD));
  GIPSI_PETSC(VecGhostGetLocalForm(shared, &local));
  GIPSI_PETSC(VecGetArray(local, &a));
  for (Index i = owned; i < n; ++i)
    for (int k = 0; k < c; ++k) values(k, i) = a[c * i + k];
  GIPSI_PETSC(VecRestoreArray(local, &a));
  GIPSI_PETSC(VecGhostRestoreLocalForm(shared, &local));
}

WholeDomainView::Layout WholeDomainView::MakeLayout(const std::vector<int>& whole_of_local,
                                                    std::int64_t owned, MPI_Comm comm) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  Layout layout;
  layout.counts.resize(static_cast<std::size_t>(size));
  layout.offsets.assign(static_cast<std::size_t>(size), 0);
  const int mine = static_cast<int>(owned);
  MPI_Allgather(&mine, 1, MPI_INT, layout.counts.data(), 1, MPI_INT, comm);
  std::partial_sum(layout.counts.begin(), layout.counts.end() - 1, layout.offsets.begin() + 1);
  layout.whole.resize(static_cast<std::size_t>(layout.offsets.back() + layout.counts.back()));
  MPI_Allgatherv(whole_of_local.data(), mine, MPI_INT, layout.whole.data(), layout.counts.data(),
                 layout.offsets.data(), MPI_INT, comm);
  layout.owned = mine;
  layout.owned_local.assign(layout.whole.size(), -1);
  for (int i = 0; i < mine; ++i)
    layout.owned_local[static_cast<std::size_t>(whole_of_local[static_cast<std::size_t>(i)])] = i;
  return layout;
}

WholeDomainView::WholeDomainView(std::unique_ptr<SimObject> part, const MeshPart& mesh_part,
                                 std::shared_ptr<const Mesh> whole, MPI_Comm comm,
                                 std::optional<BoundaryMap> boundary)
    : SimObject(std::string(part->name())),
      part_(std::move(part)),
      mesh_part_(mesh_part),
      comm_(comm) {
  SetGeometry(whole, MakeBoundary(*whole));
  whole_vertices_ = SimObject::boundary().num_vertices();
  whole_faces_ = SimObject::boundary().num_triangles();
  for (std::size_t f = 0; f < part_->fields().size(); ++f) {
    const FieldInfo& info = part_->fields()[f];
    if (info.location == FieldLocation::kBoundaryVertex ||
        info.location == FieldLocation::kBoundaryFace)
      continue;
    DeclareField(info);
    part_field_.emplace_back(static_cast<std::int64_t>(f));
  }
  nodes_ = MakeLayout(mesh_part_.whole_node, mesh_part_.num_owned, comm_);
  // Every local tet is this rank's own (tets are not shared).
  elements_ = MakeLayout(mesh_part_.whole_tet,
                         static_cast<std::int64_t>(mesh_part_.whole_tet.size()), comm_);
  Describe();
  if (boundary) MapBoundary(std::move(*boundary));
}

WholeDomainView::WholeDomainView(std::unique_ptr<SimObject> part, const MeshPart& mesh_part,
                                 MPI_Comm comm, std::optional<BoundaryMap> boundary)
    : SimObject(std::string(part->name())),
      part_(std::move(part)),
      mesh_part_(mesh_part),
      comm_(comm),
      part_only_(true) {
  SetGeometry(mesh_part_.mesh, part_->boundary());
  // The store of conditions is the part's boundary's (SetGeometry sized it); its checkpoints
  // name the whole boundary's items, so they restore on another partition. Without a
  // BoundaryMap nothing sets conditions (the factory's rule) and an empty store keeps the
  // checkpoints free of the part's boundary.
  if (boundary) {
    GIPSI_CHECK(static_cast<Index>(boundary->vertex.size()) == part_->boundary().num_vertices() &&
                static_cast<Index>(boundary->face.size()) == part_->boundary().num_triangles());
    bc_vertex_ = std::move(boundary->vertex);
    bc_face_ = std::move(boundary->face);
    whole_vertices_ = boundary->whole_vertices;
    whole_faces_ = boundary->whole_faces;
    forward_bcs_ = true;
    const std::vector<int>& v2n = part_->boundary().vertex_to_node;
    owned_vertices_ = static_cast<std::size_t>(std::count_if(
        v2n.begin(), v2n.end(), [this](int node) { return node < mesh_part_.num_owned; }));
    GIPSI_CHECK(std::all_of(v2n.begin(), v2n.begin() + static_cast<std::ptrdiff_t>(owned_vertices_),
                            [this](int node) { return node < mesh_part_.num_owned; }),
                "'{}': the owned boundary vertices are not the part's first", name());
  } else {
    boundary_conditions() = BoundaryConditions();
  }
  for (std::size_t f = 0; f < part_->fields().size(); ++f) {
    DeclareField(part_->fields()[f]);
    part_field_.emplace_back(static_cast<std::int64_t>(f));
  }
  // ReadWholeNodes finds the owned nodes by binary search in their whole-mesh indices.
  GIPSI_CHECK(std::is_sorted(mesh_part_.whole_node.begin(),
                             mesh_part_.whole_node.begin() + mesh_part_.num_owned),
              "'{}': the owned nodes are not in the whole mesh's order", name());
  Describe();
}

void WholeDomainView::Describe() {
  const auto [low, high] = WholeBoundingBox(mesh_part_, comm_);
  whole_diagonal_ = (high - low).norm();
  region_tolerance_ = RegionTolerance(low, high);
  // FNV-1a over the local nodes' and tets' whole-mesh indices and the owned count: the same
  // number only for the same cut of the same mesh (checkpoints, RestoreObjectState).
  std::uint64_t h = 14695981039346656037ULL;
  auto add = [&h](std::int64_t value) {
    for (int byte = 0; byte < 8; ++byte) {
      h ^= static_cast<std::uint64_t>(value >> (8 * byte)) & 0xFFU;
      h *= 1099511628211ULL;
    }
  };
  add(mesh_part_.num_owned);
  for (const int i : mesh_part_.whole_node) add(i);
  add(-1);
  for (const int i : mesh_part_.whole_tet) add(i);
  partition_fingerprint_ = h;
}

PointMap WholeDomainView::LocateWhole(const Points& targets) const {
  if (!part_only_) return MapFromNodes(targets);
  const Mesh& mesh = *mesh_part_.mesh;
  const PointMap local = PointMap::BarycentricInTets(mesh.nodes, mesh.tets, targets);
  const Index n = targets.cols();
  // Each point from the rank whose part is nearest to it (0 inside), the lowest on a tie.
  struct Nearest {
    double distance;
    int rank;
  };
  std::vector<Nearest> nearest(static_cast<std::size_t>(n));
  for (Index j = 0; j < n; ++j) {
    Vec3 at = Vec3::Zero();
    for (int k = 0; k < 4; ++k) at += local.weights()(k, j) * mesh.nodes.col(local.indices()(k, j));
    nearest[static_cast<std::size_t>(j)] = {(at - targets.col(j)).norm(), mesh_part_.rank};
  }
  MPI_Allreduce(MPI_IN_PLACE, nearest.data(), static_cast<int>(n), MPI_DOUBLE_INT, MPI_MINLOC,
                comm_);
  // The chosen rank's weights and whole-mesh nodes, zero elsewhere: the sums are its values.
  Eigen::Matrix4Xi nodes = Eigen::Matrix4Xi::Zero(4, n);
  Eigen::Matrix4Xd weights = Eigen::Matrix4Xd::Zero(4, n);
  double farthest = 0;
  for (Index j = 0; j < n; ++j) {
    const Nearest& p = nearest[static_cast<std::size_t>(j)];
    farthest = std::max(farthest, p.distance);
    if (p.rank != mesh_part_.rank) continue;
    for (int k = 0; k < 4; ++k) {
      nodes(k, j) = mesh_part_.whole_node[static_cast<std::size_t>(local.indices()(k, j))];
      weights(k, j) = local.weights()(k, j);
    }
  }
  MPI_Allreduce(MPI_IN_PLACE, nodes.data(), static_cast<int>(nodes.size()), MPI_INT, MPI_SUM,
                comm_);
  MPI_Allreduce(MPI_IN_PLACE, weights.data(), static_cast<int>(weights.size()), MPI_DOUBLE, MPI_SUM,
                comm_);
  return PointMap::FromWeights(std::move(nodes), std::move(weights), farthest);
}

std::vector<int> WholeDomainView::SelectWholeNodes(const Region& region) const {
  if (!part_only_) return SelectNodes(region, domain());
  if (const auto* ids = std::get_if<NodeIdsRegion>(&region)) {
    std::vector<int> out = ids->ids;
    for (std::size_t i = 0; i < out.size(); ++i)
      if (out[i] < 0 || out[i] >= mesh_part_.num_global_nodes)
        throw InputError(fmt::format("node id {} (ids[{}]) out of range [0, {})", out[i], i,
                                     mesh_part_.num_global_nodes));
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  // Every rank's selection: a triangle or tet group names a node only on the ranks that hold
  // its triangle or tet.
  return GatherSelectedNodes(mesh_part_, SelectNodes(region, *mesh_part_.mesh, region_tolerance_),
                             comm_);
}

std::vector<int> WholeDomainView::SelectLocalNodes(const Region& region) const {
  if (!part_only_ && std::holds_alternative<NodeIdsRegion>(region))
    return LocalNodesOf(mesh_part_, SelectNodes(region, domain()));  // range-checked there
  return SelectPartNodes(region, mesh_part_, region_tolerance_, comm_);
}

std::vector<int> WholeDomainView::SelectOwnedNodes(const Region& region) const {
  std::vector<int> local = SelectLocalNodes(region);
  std::erase_if(local, [this](int i) { return i >= mesh_part_.num_owned; });
  return local;
}

std::vector<int> WholeDomainView::SelectOwnedBoundaryVertices(const Region& region) const {
  // A view with its whole mesh has boundary fields only with a BoundaryMap (MapBoundary): its
  // part's boundary is then its share of the whole boundary, as a part-only view's.
  GIPSI_CHECK(part_only_ || forward_bcs_, "'{}': no boundary fields on its part", name());
  return BoundaryVerticesOfNodes(part_->boundary(), SelectOwnedNodes(region));
}

PartitionedObject::ConditionItems WholeDomainView::SelectConditionItems(const Region& region,
                                                                        bool faces) const {
  if (!forward_bcs_)
    throw InputError(
        fmt::format("object '{}' ({}, split over the processes) takes no boundary conditions",
                    name(), type_name()));
  ConditionItems out;
  if (!part_only_) {
    out.items = faces ? SelectBoundaryFaces(region, domain(), boundary())
                      : SelectBoundaryVertices(region, domain(), boundary());
    out.whole_count = static_cast<std::int64_t>(out.items.size());
    return out;
  }
  // Every part holding a selected vertex selects it; its owner counts it. A face is one part's.
  const BoundarySurface& part_boundary = part_->boundary();
  out.items =
      faces ? SelectPartBoundaryFaces(region, mesh_part_, part_boundary, region_tolerance_, comm_)
            : BoundaryVerticesOfNodes(part_boundary, SelectLocalNodes(region));
  std::sort(out.items.begin(), out.items.end());
  auto counted =
      static_cast<std::int64_t>(faces ? out.items.size()
                                      : static_cast<std::size_t>(std::count_if(
                                            out.items.begin(), out.items.end(), [this](int v) {
                                              return static_cast<std::size_t>(v) < owned_vertices_;
                                            })));
  MPI_Allreduce(MPI_IN_PLACE, &counted, 1, MPI_INT64_T, MPI_SUM, comm_);
  out.whole_count = counted;
  return out;
}

void WholeDomainView::ReadOwnedNodes(FieldId id, std::span<const int> local,
                                     Eigen::Ref<Eigen::MatrixXd> out) const {
  part_->ReadFieldItems(part_field_[static_cast<std::size_t>(id.value())], local, out);
}

void WholeDomainView::CombineAcross(std::span<double> values, Combine how) const {
  const MPI_Op op = how == Combine::kSum ? MPI_SUM : how == Combine::kMin ? MPI_MIN : MPI_MAX;
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, op,
                comm_);
}

void WholeDomainView::ReadWholeNodes(FieldId id, std::span<const int> nodes,
                                     Eigen::Ref<Eigen::MatrixXd> out) const {
  if (!part_only_) {
    ReadFieldItems(id, nodes, out);
    return;
  }
  const FieldId part_id = part_field_[static_cast<std::size_t>(id.value())];
  const FieldInfo& info = part_->field_info(part_id);
  GIPSI_CHECK(info.location == FieldLocation::kNode, "'{}': field '{}' is not a node field", name(),
              info.name);
  const int c = info.components;
  GIPSI_CHECK(out.rows() == c && out.cols() == static_cast<Index>(nodes.size()));
  // The asked nodes this rank owns, read from the part; every other entry zero, so the sum
  // over the ranks is each node's owner's value.
  const auto owned_begin = mesh_part_.whole_node.begin();
  const auto owned_end = owned_begin + mesh_part_.num_owned;
  local_items_.clear();
  positions_.clear();
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    const auto it = std::lower_bound(owned_begin, owned_end, nodes[k]);
    if (it == owned_end || *it != nodes[k]) continue;
    local_items_.push_back(static_cast<int>(it - owned_begin));
    positions_.push_back(static_cast<int>(k));
  }
  local_.resize(c, static_cast<Index>(local_items_.size()));
  part_->ReadFieldItems(part_id, local_items_, local_);
  receive_.assign(nodes.size() * static_cast<std::size_t>(c), 0.0);
  for (std::size_t i = 0; i < positions_.size(); ++i)
    for (int j = 0; j < c; ++j)
      receive_[static_cast<std::size_t>(positions_[i]) * static_cast<std::size_t>(c) +
               static_cast<std::size_t>(j)] = local_(j, static_cast<Index>(i));
  MPI_Allreduce(MPI_IN_PLACE, receive_.data(), static_cast<int>(receive_.size()), MPI_DOUBLE,
                MPI_SUM, comm_);
  for (std::size_t k = 0; k < nodes.size(); ++k)
    for (int j = 0; j < c; ++j)
      out(j, static_cast<Index>(k)) =
          receive_[k * static_cast<std::size_t>(c) + static_cast<std::size_t>(j)];
}

std::vector<std::string> WholeDomainView::cavity_names() const {
  const auto* wall = dynamic_cast<const CavityWall*>(part_.get());
  return wall != nullptr ? wall->cavity_names() : std::vector<std::string>{};
}

void WholeDomainView::AttachCavityLaw(std::string_view cavity, CavityLaw* law) {
  auto* wall = dynamic_cast<CavityWall*>(part_.get());
  if (wall == nullptr)
    throw InputError(fmt::format("object '{}' ({}) has no cavities", name(), type_name()));
  wall->AttachCavityLaw(cavity, law);
}

void WholeDomainView::BeginMacroStep() {
  SimObject::BeginMacroStep();
  part_->BeginMacroStep();
}

void WholeDomainView::MapBoundary(BoundaryMap map) {
  GIPSI_CHECK(static_cast<Index>(map.vertex.size()) == part_->boundary().num_vertices() &&
              static_cast<Index>(map.face.size()) == part_->boundary().num_triangles());
  bc_vertex_ = std::move(map.vertex);
  bc_face_ = std::move(map.face);
  forward_bcs_ = true;
  // A boundary vertex is owned with its node; the owned nodes come first, and so do their
  // boundary vertices. Every face belongs to one tet, so to one rank.
  const std::vector<int>& v2n = part_->boundary().vertex_to_node;
  owned_vertices_ = static_cast<std::size_t>(std::count_if(
      v2n.begin(), v2n.end(), [this](int node) { return node < mesh_part_.num_owned; }));
  boundary_vertices_ = MakeLayout(bc_vertex_, static_cast<std::int64_t>(owned_vertices_), comm_);
  boundary_faces_ = MakeLayout(bc_face_, static_cast<std::int64_t>(bc_face_.size()), comm_);
  for (std::size_t f = 0; f < part_->fields().size(); ++f) {
    const FieldInfo& info = part_->fields()[f];
    if (info.location != FieldLocation::kBoundaryVertex &&
        info.location != FieldLocation::kBoundaryFace)
      continue;
    DeclareField(info);
    part_field_.emplace_back(static_cast<std::int64_t>(f));
  }
}

const WholeDomainView::Layout& WholeDomainView::LayoutOf(FieldLocation location) const {
  switch (location) {
    case FieldLocation::kNode:
      return nodes_;
    case FieldLocation::kBoundaryVertex:
      return boundary_vertices_;
    case FieldLocation::kBoundaryFace:
      return boundary_faces_;
    default:
      return elements_;
  }
}

const std::vector<int>& WholeDomainView::WholeOfLocal(FieldLocation location) const {
  switch (location) {
    case FieldLocation::kNode:
      return mesh_part_.whole_node;
    case FieldLocation::kBoundaryVertex:
      return bc_vertex_;
    case FieldLocation::kBoundaryFace:
      return bc_face_;
    default:
      return mesh_part_.whole_tet;
  }
}

void WholeDomainView::CopyBoundaryConditions() {
  const BoundaryConditions& from = boundary_conditions();
  BoundaryConditions& to = part_->boundary_conditions();
  // The view's item of each part vertex and face: the same one for a part-only view (its store
  // is the part's boundary's), the whole boundary's for the other.
  auto vertex = [this](std::size_t v) {
    return static_cast<Index>(part_only_ ? v : static_cast<std::size_t>(bc_vertex_[v]));
  };
  auto face = [this](std::size_t f) {
    return static_cast<Index>(part_only_ ? f : static_cast<std::size_t>(bc_face_[f]));
  };
  // The applied part when it changed. Its copy takes the view's stamp: the part's conditions
  // are a function of the view's, so equal stamps still mean equal contents.
  if (part_only_) {
    to.SetApplied(from.applied());
  } else if (to.applied().stamp != from.applied().stamp) {
    BoundaryConditions::Applied applied = to.applied();
    const BoundaryConditions::Applied& whole = from.applied();
    std::array<double, BoundaryConditions::Applied::kVertexRow> row{};
    for (std::size_t v = 0; v < bc_vertex_.size(); ++v) {
      whole.VertexRow(vertex(v), row.data());
      applied.SetVertexRow(static_cast<Index>(v), row.data());
    }
    for (std::size_t f = 0; f < bc_face_.size(); ++f) {
      whole.FaceRow(face(f), row.data());
      applied.SetFaceRow(static_cast<Index>(f), row.data());
    }
    applied.stamp = whole.stamp;
    to.SetApplied(applied);
  }
  // The coupling loads (connectors'), every step.
  to.ClearCouplingLoads();
  for (std::size_t v = 0; v < bc_vertex_.size(); ++v) {
    const Index w = vertex(v);
    const Vec3 coupling = from.force(w) - Vec3(from.applied().force.col(w));
    if (coupling.squaredNorm() > 0) to.AddCouplingForce(static_cast<Index>(v), coupling);
  }
  for (std::size_t f = 0; f < bc_face_.size(); ++f) {
    const Index w = face(f);
    const double coupling = from.pressure(w) - from.applied().pressure[w];
    if (coupling != 0) to.AddCouplingPressure(static_cast<Index>(f), coupling);
  }
}

StepStatus WholeDomainView::DoStep(double t, double dt) {
  if (forward_bcs_) CopyBoundaryConditions();
  part_->SetTime(t);  // the view's clock is the kernel's
  return part_->Step(dt);
}

void WholeDomainView::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  const FieldId part_id = part_field_[static_cast<std::size_t>(id.value())];
  const FieldInfo& info = part_->field_info(part_id);
  if (info.location == FieldLocation::kGlobal || part_only_) {
    part_->ReadField(part_id, out);
    return;
  }
  ++whole_field_reads_;
  const Layout& layout = LayoutOf(info.location);
  const int c = info.components;
  local_.resize(c, part_->FieldCount(part_id));
  part_->ReadField(part_id, local_);
  counts_.resize(layout.counts.size());
  offsets_.resize(layout.offsets.size());
  for (std::size_t r = 0; r < counts_.size(); ++r) {
    counts_[r] = c * layout.counts[r];
    offsets_[r] = c * layout.offsets[r];
  }
  receive_.resize(layout.whole.size() * static_cast<std::size_t>(c));
  // The owned items are the first local ones: their values are the first columns of local_.
  MPI_Allgatherv(local_.data(), c * layout.owned, MPI_DOUBLE, receive_.data(), counts_.data(),
                 offsets_.data(), MPI_DOUBLE, comm_);
  for (std::size_t i = 0; i < layout.whole.size(); ++i)
    for (int k = 0; k < c; ++k)
      out(k, layout.whole[i]) =
          receive_[i * static_cast<std::size_t>(c) + static_cast<std::size_t>(k)];
}

void WholeDomainView::DoReadFieldItems(FieldId id, std::span<const int> items,
                                       Eigen::Ref<Eigen::MatrixXd> out) const {
  const FieldId part_id = part_field_[static_cast<std::size_t>(id.value())];
  if (part_only_) {
    part_->ReadFieldItems(part_id, items, out);
    return;
  }
  const FieldInfo& info = part_->field_info(part_id);
  const Layout& layout = LayoutOf(info.location);
  const int c = info.components;
  local_.resize(c, part_->FieldCount(part_id));
  part_->ReadField(part_id, local_);
  // The asked items this rank owns: their positions in `items` and their values.
  sent_items_.clear();
  sent_values_.clear();
  for (std::size_t k = 0; k < items.size(); ++k) {
    const int local = layout.owned_local[static_cast<std::size_t>(items[k])];
    if (local < 0) continue;
    sent_items_.push_back(static_cast<int>(k));
    for (int j = 0; j < c; ++j) sent_values_.push_back(local_(j, local));
  }
  const int size = static_cast<int>(layout.counts.size());
  counts_.resize(static_cast<std::size_t>(size));
  offsets_.assign(static_cast<std::size_t>(size), 0);
  const int mine = static_cast<int>(sent_items_.size());
  MPI_Allgather(&mine, 1, MPI_INT, counts_.data(), 1, MPI_INT, comm_);
  std::partial_sum(counts_.begin(), counts_.end() - 1, offsets_.begin() + 1);
  received_items_.resize(static_cast<std::size_t>(offsets_.back() + counts_.back()));
  GIPSI_CHECK(received_items_.size() == items.size(), "'{}': {} of {} items owned by some rank",
              name(), received_items_.size(), items.size());
  MPI_Allgatherv(sent_items_.data(), mine, MPI_INT, received_items_.data(), counts_.data(),
                 offsets_.data(), MPI_INT, comm_);
  for (int r = 0; r < size; ++r) {
    counts_[static_cast<std::size_t>(r)] *= c;
    offsets_[static_cast<std::size_t>(r)] *= c;
  }
  receive_.resize(items.size() * static_cast<std::size_t>(c));
  MPI_Allgatherv(sent_values_.data(), c * mine, MPI_DOUBLE, receive_.data(), counts_.data(),
                 offsets_.data(), MPI_DOUBLE, comm_);
  for (std::size_t i = 0; i < received_items_.size(); ++i)
    for (int j = 0; j < c; ++j)
      out(j, received_items_[i]) =
          receive_[i * static_cast<std::size_t>(c) + static_cast<std::size_t>(j)];
}

void WholeDomainView::DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) {
  const FieldId part_id = part_field_[static_cast<std::size_t>(id.value())];
  const FieldInfo& info = part_->field_info(part_id);
  if (info.location == FieldLocation::kGlobal || part_only_) {
    part_->WriteField(part_id, in);
    return;
  }
  const std::vector<int>& whole_of_local = WholeOfLocal(info.location);
  local_.resize(info.components, static_cast<Index>(whole_of_local.size()));
  for (std::size_t i = 0; i < whole_of_local.size(); ++i)
    local_.col(static_cast<Index>(i)) = in.col(whole_of_local[i]);
  part_->WriteField(part_id, local_);
}

}  // namespace gipsi
