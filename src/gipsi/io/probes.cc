#include "gipsi/io/probes.h"

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <array>
#include <limits>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/file_io.h"
#include "gipsi/base/units.h"
#include "gipsi/geometry/region_json.h"
#include "gipsi/io/sample_times.h"

namespace gipsi {
namespace {

/// Values per CSV row after time.
std::size_t ProbeWidth(const Probe& probe) {
  std::size_t width = probe.is_line() ? 4 : 0;
  for (FieldId id : probe.fields) width += std::size_t(probe.object->field_info(id).components);
  return width;
}

/// Interpolation at the probe's points that never blends the field's no-data marker.
void Interpolate(const PointMap& map, const FieldInfo& info, const Eigen::MatrixXd& values,
                 Eigen::MatrixXd& out) {
  if (info.no_data)
    map.ApplyMarked(values, out, *info.no_data);
  else
    map.Apply(values, out);
}

/// The probe's point map rewritten over the nodes it uses (sorted, into probe.items): a sample
/// then reads those nodes only. Every slot keeps its node, the unused ones (weight 0) too, so
/// the interpolation adds the same numbers as over the whole field.
void UseOnlyTheMappedNodes(Probe& probe) {
  const PointMap& map = *probe.point;
  probe.nodes = map.indices();
  const Eigen::Matrix4Xi& nodes = map.indices();
  probe.items.assign(nodes.data(), nodes.data() + nodes.size());
  std::sort(probe.items.begin(), probe.items.end());
  probe.items.erase(std::unique(probe.items.begin(), probe.items.end()), probe.items.end());
  Eigen::Matrix4Xi columns(4, nodes.cols());
  for (Index j = 0; j < nodes.cols(); ++j)
    for (int k = 0; k < 4; ++k)
      columns(k, j) =
          static_cast<int>(std::lower_bound(probe.items.begin(), probe.items.end(), nodes(k, j)) -
                           probe.items.begin());
  probe.point = PointMap::FromWeights(std::move(columns), map.weights(), map.max_distance());
}

}  // namespace

std::string Probe::Header() const {
  std::string header = is_line() ? "time,distance,x,y,z" : "time";
  for (FieldId id : fields) {
    const FieldInfo& info = object->field_info(id);
    if (info.components == 1) {
      header += "," + info.name;
    } else if (info.components == 3) {
      for (const char* axis : {"x", "y", "z"}) header += fmt::format(",{}_{}", info.name, axis);
    } else {
      for (int c = 0; c < info.components; ++c)
        header += fmt::format(",{}_{}{}", info.name, c % 3, c / 3);
    }
  }
  return header;
}

void Probe::ReadItems(FieldId id, Eigen::MatrixXd& values) const {
  if (owners != nullptr)
    owners->ReadOwnedNodes(id, items, values);
  else if (partitioned != nullptr)
    partitioned->ReadWholeNodes(id, items, values);
  else
    object->ReadFieldItems(id, items, values);
}

void Probe::Sample(std::vector<double>& out) const {
  out.clear();
  if (is_line()) {
    const std::size_t width = ProbeWidth(*this);
    const Index n = line.cols();
    out.assign(width * std::size_t(n), 0.0);
    for (Index j = 0; j < n; ++j) {
      double* row = out.data() + width * std::size_t(j);
      row[0] = distance[std::size_t(j)];
      for (int k = 0; k < 3; ++k) row[1 + k] = line(k, j);
    }
    std::size_t column = 4;
    for (FieldId id : fields) {
      const FieldInfo& info = object->field_info(id);
      Eigen::MatrixXd values(info.components, static_cast<Index>(items.size()));
      ReadItems(id, values);
      Eigen::MatrixXd at_points(info.components, n);
      Interpolate(*point, info, values, at_points);
      if (info.location == FieldLocation::kNode)
        object->CorrectInterpolated(id, nodes, point->weights(), at_points);
      for (Index j = 0; j < n; ++j)
        for (int c = 0; c < info.components; ++c)
          out[width * std::size_t(j) + column + std::size_t(c)] = at_points(c, j);
      column += std::size_t(info.components);
    }
    return;
  }
  for (FieldId id : fields) {
    const FieldInfo& info = object->field_info(id);
    const bool global = info.location == FieldLocation::kGlobal;
    Eigen::MatrixXd values(info.components, global ? 1 : static_cast<Index>(items.size()));
    if (global)
      object->ReadField(id, values);
    else
      ReadItems(id, values);
    if (global) {
      for (int c = 0; c < info.components; ++c) out.push_back(values(c, 0));
    } else if (point) {
      Eigen::MatrixXd at(info.components, 1);
      Interpolate(*point, info, values, at);
      if (info.location == FieldLocation::kNode)
        object->CorrectInterpolated(id, nodes, point->weights(), at);
      for (int c = 0; c < info.components; ++c) out.push_back(at(c, 0));
    } else {
      // Per component: the reduction and how many values it took (no-data values skipped).
      const auto c = static_cast<std::size_t>(info.components);
      std::vector<double> acc(c, reduce == Reduce::kMin   ? std::numeric_limits<double>::infinity()
                                 : reduce == Reduce::kMax ? -std::numeric_limits<double>::infinity()
                                                          : 0.0);
      std::vector<double> counted(c, 0.0);
      for (std::size_t k = 0; k < c; ++k) {
        for (Index i = 0; i < values.cols(); ++i) {
          const double v = values(static_cast<Index>(k), i);
          if (info.no_data && v == *info.no_data) continue;
          ++counted[k];
          if (reduce == Reduce::kMin)
            acc[k] = std::min(acc[k], v);
          else if (reduce == Reduce::kMax)
            acc[k] = std::max(acc[k], v);
          else
            acc[k] += v;
        }
      }
      if (owners != nullptr) {  // this process's nodes of the region: combine with the others'
        using Combine = PartitionedObject::Combine;
        owners->CombineAcross(acc, reduce == Reduce::kMin   ? Combine::kMin
                                   : reduce == Reduce::kMax ? Combine::kMax
                                                            : Combine::kSum);
        owners->CombineAcross(counted, Combine::kSum);
      }
      for (std::size_t k = 0; k < c; ++k) {
        if (counted[k] == 0 && info.no_data)
          acc[k] = *info.no_data;
        else if (reduce == Reduce::kMean)
          acc[k] /= counted[k];
        out.push_back(acc[k]);
      }
    }
  }
}

Probe ParseProbe(const std::string& name, const JsonNode& node, const Kernel& kernel) {
  node.CheckKeys({"object", "point", "region", "line", "at", "fields", "field", "reduce", "every",
                  "description"});
  // The name becomes <out>/probes/<name>.csv: it must not climb out of that folder.
  const bool plain = !name.empty() && name.front() != '.' &&
                     name.find_first_of("/\\") == std::string::npos &&
                     std::all_of(name.begin(), name.end(), [](unsigned char c) { return c >= 32; });
  if (!plain)
    node.Fail(
        fmt::format("probe name '{}' must be a plain file name (no '/' or '\\', not starting "
                    "with '.')",
                    name));
  Probe probe;
  probe.name = name;
  JsonNode object_node = node.At("object");
  try {
    probe.object = &kernel.FindObject(object_node.AsString());
  } catch (const InputError& e) {
    object_node.Fail(e.what());
  }
  const SimObject& object = *probe.object;
  // An object that holds only its part of the domain (a distributed run's) is addressed
  // through its whole-domain calls.
  const auto* split = dynamic_cast<const PartitionedObject*>(&object);
  if (split != nullptr && split->holds_whole_domain()) split = nullptr;
  probe.partitioned = split;
  auto diagonal = [&object, split] {
    if (split != nullptr) return split->WholeDiagonal();
    const Mesh& mesh = object.domain();
    return (mesh.nodes.rowwise().maxCoeff() - mesh.nodes.rowwise().minCoeff()).norm();
  };
  std::vector<std::string> names;
  if (auto f = node.Find("field")) names.push_back(f->AsString());
  if (auto f = node.Find("fields")) {
    auto more = f->AsStrings();
    names.insert(names.end(), more.begin(), more.end());
  }
  if (names.empty()) node.Fail("missing required key 'fields'");
  if (int(node.Has("point")) + int(node.Has("region")) + int(node.Has("line")) > 1)
    node.Fail("give one of 'point', 'region' or 'line'");
  if (node.Has("at") && !node.Has("line"))
    node.At("at").Fail("only line probes take sample times 'at' (others use 'every')");
  if (node.Has("every") && node.Has("line"))
    node.At("every").Fail("a line probe samples at the times 'at' (or at the end), not 'every'");
  probe.every = node.Has("every") ? ReadPositiveQuantity(node.At("every"), "s", true) : 0.0;

  bool needs_location = false;
  FieldLocation location = FieldLocation::kGlobal;
  for (const auto& field_name : names) {
    FieldId id;
    try {
      id = object.FindField(field_name);
    } catch (const InputError& e) {
      node.At(node.Has("field") ? "field" : "fields").Fail(e.what());
    }
    const FieldInfo& info = object.field_info(id);
    if (!info.readable()) node.Fail(fmt::format("field '{}' is write-only", field_name));
    if (info.location != FieldLocation::kGlobal) {
      if (needs_location && info.location != location)
        node.Fail("all non-global fields of one probe must share a location");
      needs_location = true;
      location = info.location;
    }
    probe.fields.push_back(id);
  }

  if (auto p = node.Find("point")) {
    if (location != FieldLocation::kNode)
      p->Fail("point probes interpolate node fields; these fields are not node fields");
    Points target = p->AsVec3();
    probe.point = split != nullptr ? split->LocateWhole(target) : object.MapFromNodes(target);
    const double diag = diagonal();
    if (probe.point->max_distance() > 1e-6 * diag)
      p->Fail(fmt::format("the point lies {:.4g} outside the domain of '{}'",
                          probe.point->max_distance(), object.path()));
    UseOnlyTheMappedNodes(probe);
  } else if (auto l = node.Find("line")) {
    if (location != FieldLocation::kNode || !needs_location)
      node.At(node.Has("field") ? "field" : "fields")
          .Fail("line probes interpolate node fields; give node fields only");
    for (FieldId id : probe.fields)
      if (object.field_info(id).location != FieldLocation::kNode)
        node.At(node.Has("field") ? "field" : "fields")
            .Fail(fmt::format("field '{}' is not a node field; line probes interpolate node "
                              "fields only",
                              object.field_info(id).name));
    l->CheckKeys({"from", "to", "points"});
    const Vec3 from = l->At("from").AsVec3(), to = l->At("to").AsVec3();
    const JsonNode points_node = l->At("points");
    const auto n = points_node.AsInt();
    if (n < 2 || n > 100000) points_node.Expected("a number of points in [2, 100000]");
    if (!((to - from).norm() > 0)) l->At("to").Fail("the line has zero length ('to' = 'from')");
    probe.line.resize(3, n);
    probe.distance.resize(std::size_t(n));
    for (Index j = 0; j < n; ++j) {
      const double s = double(j) / double(n - 1);
      probe.line.col(j) = (1 - s) * from + s * to;
      probe.distance[std::size_t(j)] = s * (to - from).norm();
    }
    probe.point =
        split != nullptr ? split->LocateWhole(probe.line) : object.MapFromNodes(probe.line);
    const double diag = diagonal();
    if (probe.point->max_distance() > 1e-6 * diag)
      l->Fail(fmt::format("the line leaves the domain of '{}' (a point lies {:.4g} outside it)",
                          object.path(), probe.point->max_distance()));
    UseOnlyTheMappedNodes(probe);
    if (auto at = node.Find("at")) {
      if (at->is_array()) {
        for (const auto& item : at->Items())
          probe.at.push_back(ReadPositiveQuantity(item, "s", /*allow_zero=*/true));
        if (probe.at.empty()) at->Expected("a time or a non-empty array of times");
        if (!std::is_sorted(probe.at.begin(), probe.at.end()) ||
            std::adjacent_find(probe.at.begin(), probe.at.end()) != probe.at.end())
          at->Expected("increasing times");
      } else {
        probe.at.push_back(ReadPositiveQuantity(*at, "s", /*allow_zero=*/true));
      }
    }
  } else if (auto r = node.Find("region")) {
    probe.region = true;
    Region region = ParseRegion(*r);
    // A split object's nodes and boundary vertices are reduced where they are owned (a vertex
    // is owned with its node), whether or not it holds its whole mesh.
    bool anywhere = false;  // some process owns a node of the region
    const auto* owners =
        location == FieldLocation::kNode || location == FieldLocation::kBoundaryVertex
            ? dynamic_cast<const PartitionedObject*>(&object)
            : nullptr;
    try {
      if (owners != nullptr) {
        probe.owners = owners;
        probe.items = location == FieldLocation::kNode
                          ? owners->SelectOwnedNodes(region)
                          : owners->SelectOwnedBoundaryVertices(region);
        std::array<double, 1> selected{static_cast<double>(probe.items.size())};
        owners->CombineAcross(selected, PartitionedObject::Combine::kSum);
        anywhere = selected[0] > 0;
      } else if (location == FieldLocation::kNode)
        probe.items = SelectNodes(region, object.domain());
      else if (location == FieldLocation::kBoundaryVertex)
        probe.items = SelectBoundaryVertices(region, object.domain(), object.boundary());
      else
        r->Fail("region probes reduce node or boundary-vertex fields");
    } catch (const InputError& e) {
      r->Fail(e.what());
    }
    if (probe.owners == nullptr ? probe.items.empty() : !anywhere)
      r->Fail("the region selects nothing");
    if (auto reduce = node.Find("reduce")) {
      std::string s = reduce->AsChoice({"mean", "sum", "min", "max"});
      probe.reduce = s == "sum"   ? Probe::Reduce::kSum
                     : s == "min" ? Probe::Reduce::kMin
                     : s == "max" ? Probe::Reduce::kMax
                                  : Probe::Reduce::kMean;
    }
  } else if (needs_location) {
    node.Fail("non-global fields need a 'point' or a 'region'");
  }
  return probe;
}

ProbeRecorder::ProbeRecorder(std::vector<Probe> probes, const std::filesystem::path& directory,
                             bool resume, bool read_only)
    : write_(!read_only) {
  if (write_) std::filesystem::create_directories(directory);
  for (auto& probe : probes) {
    auto path = directory / (probe.name + ".csv");
    Stream stream{std::move(probe), {}, 0, 0, path};
    if (write_ && !resume) {  // a resumed run opens its files once the checkpoint is restored
      stream.file.open(path, std::ios::out | std::ios::trunc);
      if (!stream.file)
        throw OutputError(
            fmt::format("{}: cannot create the file: {}", path.string(), std::strerror(errno)));
      stream.file << stream.probe.Header() << '\n';
      stream.file.precision(17);
    }
    streams_.push_back(std::move(stream));
  }
}

void ProbeRecorder::Write(Stream& s, double t) {
  s.probe.Sample(row_);
  if (!write_) return;  // sampled (collective for a distributed object), not written
  const std::size_t width = ProbeWidth(s.probe);
  for (std::size_t start = 0; start < row_.size(); start += width) {  // line probes: n rows
    s.file << t;
    for (std::size_t k = start; k < start + width; ++k) s.file << ',' << row_[k];
    s.file << '\n';
  }
  errno = 0;
  s.file.flush();
  if (!s.file)
    throw OutputError(fmt::format("{}: cannot write: {}", s.path.string(),
                                  errno != 0 ? std::strerror(errno) : "the stream failed"));
}

void ProbeRecorder::Observe(const Kernel& kernel, double t) {
  const double tolerance = 1e-9 * kernel.macro_dt();
  for (auto& s : streams_) {
    if (s.probe.is_line()) {
      if (s.next_at < s.probe.at.size() && t + tolerance >= s.probe.at[s.next_at]) {
        Write(s, t);
        while (s.next_at < s.probe.at.size() && t + tolerance >= s.probe.at[s.next_at]) ++s.next_at;
      }
      continue;
    }
    if (t + tolerance < s.next) continue;
    Write(s, t);
    if (s.probe.every > 0) s.next = NextSampleTime(s.next, s.probe.every, t + tolerance);
  }
}

void ProbeRecorder::Finish(const Kernel& kernel) {
  for (auto& s : streams_) {
    if (s.probe.is_line() && s.probe.at.empty() && s.next_at == 0) {
      Write(s, kernel.time());  // once, at the end of the run
      s.next_at = 1;
    }
    if (write_) s.file.flush();
  }
}

}  // namespace gipsi
