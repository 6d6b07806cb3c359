/// @file
/// SimObject checkpoints and snapshots: the base-class part (clock, step count, applied boundary
/// conditions) and the default hooks (the type's state serialised, for types without a state
/// value type).

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <optional>
#include <span>
#include <tuple>

#include "gipsi/base/error.h"
#include "gipsi/base/object_state.h"
#include "gipsi/base/state.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/core/row_state.h"
#include "gipsi/core/sim_object.h"

namespace gipsi {

namespace {

// SaveState's layout: the header, the applied boundary conditions, the type's state.
void WriteSaved(StateWriter& out, std::string_view name, std::string_view type, double time,
                std::int64_t steps, const BoundaryConditions& bcs,
                const std::function<void(StateWriter&)>& write_own) {
  out.BeginSection("SimObject", 2);
  out.WriteString(name);
  out.WriteString(type);
  out.WriteDouble(time);
  out.WriteInt(steps);
  bcs.SaveApplied(out);  // the coupling loads are not state: the next macro step clears them
  out.BeginSection(type, 1);
  write_own(out);
  out.EndSection();
  out.EndSection();
}

}  // namespace

void SimObject::SaveState(StateWriter& out) const {
  WriteSaved(out, name_, type_name(), time_, step_count_, bcs_,
             [this](StateWriter& w) { SaveObjectState(w); });
}

void SimObject::RestoreState(StateReader& in) {
  in.BeginSection("SimObject", 2);
  const std::string name = in.ReadString();
  const std::string type = in.ReadString();
  if (name != name_ || type != type_name())
    in.Fail(fmt::format("the checkpoint has object '{}' ({}) where this scene has '{}' ({})", name,
                        type, name_, type_name()));
  const double time = in.ReadDouble();
  const std::int64_t steps = in.ReadInt();
  // A distributed run's checkpoint read on one process: its conditions are placed once the
  // type's section says whose they are.
  const bool serial = dynamic_cast<const PartitionedObject*>(this) == nullptr;
  std::optional<BoundaryConditions::Applied> read;
  if (serial && !CheckpointPieces().empty())
    read = BoundaryConditions::ReadAnySize(in);
  else
    RestoreAppliedConditions(in);
  in.BeginSection(type_name(), 1);
  // A distributed run's checkpoint holds a split object's part here; a run on one process
  // reads every rank's part into the serial object.
  if (serial && in.NextIsSection(kSavedPartTag)) {
    RestoreFromPieces(in, read ? std::move(*read) : BoundaryConditions::Applied{});
  } else {
    if (read) RestoreReadConditions(in, std::move(*read));
    RestoreObjectState(in);
  }
  in.EndSection();
  in.EndSection();
  time_ = time;
  step_count_ = steps;
}

void SimObject::RestoreAppliedConditions(StateReader& in) { bcs_.RestoreApplied(in); }

void SimObject::RestoreReadConditions(StateReader& in, BoundaryConditions::Applied read) {
  const Index vertices = read.value.cols(), faces = read.pressure.size();
  if (vertices == 0 && faces == 0) return;  // a part-only view without a store set none
  if (vertices != bcs_.num_vertices() || faces != bcs_.num_faces())
    in.Fail(fmt::format(
        "boundary conditions of {} vertices and {} faces where object '{}' has {} and {}", vertices,
        faces, name_, bcs_.num_vertices(), bcs_.num_faces()));
  bcs_.RestoreApplied(std::move(read));
}

void SimObject::RestoreFromPieces(StateReader& in, BoundaryConditions::Applied conditions) {
  const auto* rows_of = dynamic_cast<const RowState*>(this);
  const std::vector<std::filesystem::path> pieces = CheckpointPieces();
  if (rows_of == nullptr)
    in.Fail(
        fmt::format("object '{}' was split over the ranks of a distributed run, and a {} "
                    "does not take a split object's parts: resume it with mpirun",
                    name_, type_name()));
  if (pieces.empty())
    in.Fail(
        fmt::format("object '{}' was split over the ranks of a distributed run: resume from "
                    "every rank's file (gipsi run --resume finds them)",
                    name_));
  const ItemCounts mine{domain().num_nodes(), domain().num_tets(), boundary().num_triangles()};
  const StateReader::Position at = in.position();
  StateRows whole;
  std::vector<char> node_set, tet_set, face_set;
  SavedHeader first;
  // The parts' stores of conditions (SavedConditions::kPart) gathered on the whole boundary:
  // each owned boundary vertex and each face from the part that holds it.
  BoundaryConditions::Applied gathered = bcs_.applied();
  std::vector<char> vertex_held, face_held;
  SavedConditions kept = SavedConditions::kNone;
  // Each part's rows go where its items are in the whole domain.
  auto place = [&](StateReader& from, const std::vector<double>& rows, int width,
                   std::span<const int> where, std::vector<double>& to, std::vector<char>& set,
                   std::int64_t count, const char* what) {
    if (width == 0) return;
    for (std::size_t i = 0; i < where.size(); ++i) {
      const int item = where[i];
      if (item < 0 || item >= count || set[static_cast<std::size_t>(item)] != 0)
        from.Fail(
            fmt::format("the parts do not hold every {} of this object's once ({} {}): "
                        "the checkpoint is of another mesh",
                        what, what, item));
      set[static_cast<std::size_t>(item)] = 1;
      std::copy_n(rows.begin() + static_cast<std::ptrdiff_t>(i * static_cast<std::size_t>(width)),
                  width,
                  to.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(item) *
                                                           static_cast<std::size_t>(width)));
    }
  };
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    std::optional<StateReader> other;
    BoundaryConditions::Applied part_conditions;
    if (k > 0) {
      other.emplace(ReadCheckpointFile(pieces[k]), pieces[k].string());
      part_conditions = SeekPartReadingConditions(*other, at);
    } else {
      part_conditions = std::move(conditions);
    }
    StateReader& from = k == 0 ? in : *other;
    from.BeginSection(kSavedPartTag, kSavedPartVersion);
    const SavedPart part = ReadSavedPart(from);
    if (part.size != static_cast<std::int64_t>(pieces.size()) ||
        part.rank != static_cast<std::int64_t>(k))
      from.Fail(
          fmt::format("this file holds rank {}'s part of {} where rank {}'s part of {} was "
                      "expected: the set mixes checkpoints",
                      part.rank, part.size, k, pieces.size()));
    if (k == 0) kept = part.conditions;
    if (part.conditions != kept)
      from.Fail("this file keeps the object's boundary conditions otherwise than the first");
    if (kept == SavedConditions::kWhole && k == 0) {
      RestoreReadConditions(from, std::move(part_conditions));
    } else if (kept == SavedConditions::kPart) {
      if (part.whole_vertices != bcs_.num_vertices() || part.whole_faces != bcs_.num_faces() ||
          part_conditions.value.cols() != part.boundary_vertices ||
          part_conditions.pressure.size() != part.local.faces ||
          static_cast<std::int64_t>(part.faces.size()) != part.local.faces)
        from.Fail(fmt::format(
            "the part's boundary conditions are on {} of {} boundary vertices and {} of {} faces, "
            "and object '{}' has {} and {}: the checkpoint is of another mesh",
            part_conditions.value.cols(), part.whole_vertices, part_conditions.pressure.size(),
            part.whole_faces, name_, bcs_.num_vertices(), bcs_.num_faces()));
      vertex_held.resize(static_cast<std::size_t>(bcs_.num_vertices()));
      face_held.resize(static_cast<std::size_t>(bcs_.num_faces()));
      std::array<double, BoundaryConditions::Applied::kVertexRow> row{};
      for (std::size_t v = 0; v < part.vertices.size(); ++v) {
        const int w = part.vertices[v];
        if (w < 0 || w >= bcs_.num_vertices() || vertex_held[static_cast<std::size_t>(w)] != 0)
          from.Fail(fmt::format("the parts do not hold boundary vertex {} once", w));
        vertex_held[static_cast<std::size_t>(w)] = 1;
        part_conditions.VertexRow(static_cast<Index>(v), row.data());
        gathered.SetVertexRow(w, row.data());
      }
      for (std::size_t f = 0; f < part.faces.size(); ++f) {
        const int w = part.faces[f];
        if (w < 0 || w >= bcs_.num_faces() || face_held[static_cast<std::size_t>(w)] != 0)
          from.Fail(fmt::format("the parts do not hold boundary face {} once", w));
        face_held[static_cast<std::size_t>(w)] = 1;
        part_conditions.FaceRow(static_cast<Index>(f), row.data());
        gathered.SetFaceRow(w, row.data());
      }
    }
    if (part.whole_nodes != mine.nodes || part.whole_tets != mine.tets)
      from.Fail(
          fmt::format("the checkpoint's mesh has {} nodes and {} tets, and this object's "
                      "has {} and {}",
                      part.whole_nodes, part.whole_tets, mine.nodes, mine.tets));
    StateRows rows;
    const SavedHeader header =
        ReadSavedState(from, part.boundary_vertices, part.local.faces,
                       [&](StateReader& own) { rows = rows_of->ReadStateRows(own, part.local); });
    from.EndSection();
    if (header.name != name_ || header.type != type_name())
      from.Fail(fmt::format("the checkpoint has object '{}' ({}) where this scene has '{}' ({})",
                            header.name, header.type, name_, type_name()));
    if (k == 0) {
      first = header;
      whole.node_width = rows.node_width;
      whole.tet_width = rows.tet_width;
      whole.face_width = rows.face_width;
      whole.shared = rows.shared;
      whole.node.resize(static_cast<std::size_t>(mine.nodes * rows.node_width));
      whole.tet.resize(static_cast<std::size_t>(mine.tets * rows.tet_width));
      whole.face.resize(static_cast<std::size_t>(mine.faces * rows.face_width));
      node_set.assign(static_cast<std::size_t>(mine.nodes), 0);
      tet_set.assign(static_cast<std::size_t>(mine.tets), 0);
      face_set.assign(static_cast<std::size_t>(mine.faces), 0);
    } else if (header.time != first.time || header.steps != first.steps ||
               rows.node_width != whole.node_width || rows.tet_width != whole.tet_width ||
               rows.face_width != whole.face_width || rows.shared != whole.shared) {
      from.Fail(
          "this file is from another checkpoint than the others: resume from a set "
          "written together");
    }
    if (rows.face_width > 0 && part.faces.empty())
      from.Fail("the part's boundary faces have state but no place on the whole boundary");
    place(from, rows.node, rows.node_width, part.owned, whole.node, node_set, mine.nodes, "node");
    place(from, rows.tet, rows.tet_width, part.tets, whole.tet, tet_set, mine.tets, "tet");
    place(from, rows.face, rows.face_width, part.faces, whole.face, face_set, mine.faces,
          "boundary face");
  }
  for (const auto& [set, width, what] : {std::tuple{&node_set, whole.node_width, "node"},
                                         std::tuple{&tet_set, whole.tet_width, "tet"},
                                         std::tuple{&face_set, whole.face_width, "boundary face"}})
    if (width > 0 && std::ranges::find(*set, 0) != set->end())
      in.Fail(
          fmt::format("the parts do not hold every {} of this object's: the checkpoint is of "
                      "another mesh",
                      what));
  if (kept == SavedConditions::kPart) {
    if (std::ranges::find(vertex_held, 0) != vertex_held.end() ||
        std::ranges::find(face_held, 0) != face_held.end())
      in.Fail(
          "the parts do not hold every boundary vertex and face of this object's: the "
          "checkpoint is of another mesh");
    bcs_.RestoreApplied(std::move(gathered));
  }
  StateWriter bytes;
  rows_of->WriteStateRows(bytes, whole);
  StateReader own(bytes.TakeBytes(),
                  fmt::format("object '{}' gathered from {} parts", name_, pieces.size()));
  RestoreObjectState(own);
}

SimObject::SavedHeader SimObject::ReadSavedState(
    StateReader& in, Index boundary_vertices, Index boundary_faces,
    const std::function<void(StateReader&)>& read_own) {
  SavedHeader header;
  in.BeginSection("SimObject", 2);
  header.name = in.ReadString();
  header.type = in.ReadString();
  header.time = in.ReadDouble();
  header.steps = in.ReadInt();
  BoundaryConditions(boundary_vertices, boundary_faces).RestoreApplied(in);
  in.BeginSection(header.type, 1);
  read_own(in);
  in.EndSection();
  in.EndSection();
  return header;
}

void SimObject::RestoreStateFrom(double time, std::int64_t steps,
                                 const std::function<void(StateWriter&)>& write_own) {
  StateWriter out;
  WriteSaved(out, name_, type_name(), time, steps, bcs_, write_own);
  StateReader in(out.TakeBytes(), fmt::format("object '{}' moved to this partition", name_));
  RestoreState(in);
}

namespace {

/// What SimObject::TakeSnapshot copies: the clock, the step count, the applied boundary
/// conditions (only when their stamp changed) and the type's own state.
class SimObjectSnapshot final : public TypedState<SimObjectSnapshot> {
 public:
  SimObjectSnapshot(const SimObject* object, std::unique_ptr<ObjectState> own)
      : object(object), own(std::move(own)) {}

  void Assign(const ObjectState& other) override {
    const SimObjectSnapshot& o = Of(other);
    GIPSI_CHECK(o.object == object, "a snapshot of another object");
    time = o.time;
    steps = o.steps;
    if (bcs.stamp != o.bcs.stamp) bcs = o.bcs;
    own->Assign(*o.own);
  }
  [[nodiscard]] std::string FirstDifference(const ObjectState& other) const override {
    const SimObjectSnapshot& o = Of(other);
    if (!state_detail::SameBits(&time, &o.time, 1)) return "time";
    if (steps != o.steps) return "step count";
    std::string d = gipsi::FirstDifference(bcs, o.bcs);
    if (!d.empty()) return "boundary conditions: " + d;
    return own->FirstDifference(*o.own);
  }

  const SimObject* object;
  double time = 0;
  std::int64_t steps = 0;
  BoundaryConditions::Applied bcs;
  std::unique_ptr<ObjectState> own;
};

}  // namespace

std::unique_ptr<ObjectState> SimObject::NewSnapshot() const {
  auto box = std::make_unique<SimObjectSnapshot>(this, NewObjectState());
  TakeSnapshot(*box);
  return box;
}

void SimObject::TakeSnapshot(ObjectState& into) const {
  SimObjectSnapshot& s = SimObjectSnapshot::Of(into);
  GIPSI_CHECK(s.object == this, "object '{}': a snapshot of another object", name_);
  s.time = time_;
  s.steps = step_count_;
  if (s.bcs.stamp != bcs_.applied().stamp) s.bcs = bcs_.applied();
  CopyObjectState(*s.own);
}

void SimObject::RestoreSnapshot(const ObjectState& from) {
  const SimObjectSnapshot& s = SimObjectSnapshot::Of(from);
  GIPSI_CHECK(s.object == this, "object '{}': a snapshot of another object", name_);
  time_ = s.time;
  step_count_ = s.steps;
  bcs_.SetApplied(s.bcs);
  SetObjectState(*s.own);
}

std::unique_ptr<ObjectState> SimObject::NewObjectState() const {
  if (state_binding_) return state_binding_->New();
  return std::make_unique<ByteState>();
}

void SimObject::CopyObjectState(ObjectState& into) const {
  if (state_binding_) {
    state_binding_->Copy(into);
    return;
  }
  StateWriter out;
  out.BeginSection(type_name(), 1);
  SaveObjectState(out);
  out.EndSection();
  ByteState::Of(into).bytes = out.TakeBytes();
}

void SimObject::SetObjectState(const ObjectState& from) {
  if (state_binding_) {
    state_binding_->Set(from);
    DropStateCache();
    StateRestored();
    return;
  }
  StateReader in(ByteState::Of(from).bytes, fmt::format("the snapshot of object '{}'", name_));
  in.BeginSection(type_name(), 1);
  RestoreObjectState(in);
  in.EndSection();
}

void SimObject::SaveObjectState(StateWriter& out) const {
  if (state_binding_) {
    state_binding_->Write(out);
    SaveStateCache(out);
    return;
  }
  throw InputError(
      fmt::format("object '{}': object type {} does not support checkpoints", name_, type_name()));
}

void SimObject::RestoreObjectState(StateReader& in) {
  if (state_binding_) {
    state_binding_->Read(in, [this](StateReader& r) { RestoreStateCache(r); });
    StateRestored();
    return;
  }
  throw InputError(
      fmt::format("object '{}': object type {} does not support checkpoints", name_, type_name()));
}

}  // namespace gipsi
