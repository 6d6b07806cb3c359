#include "gipsi/io/probes.h"

#include <algorithm>
#include <limits>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/units.h"
#include "gipsi/geometry/region_json.h"

namespace gipsi {

std::string Probe::Header() const {
  std::string header = "time";
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

void Probe::Sample(std::vector<double>& out) const {
  out.clear();
  for (FieldId id : fields) {
    const FieldInfo& info = object->field_info(id);
    Eigen::MatrixXd values(info.components, object->FieldCount(id));
    object->ReadField(id, values);
    if (info.location == FieldLocation::kGlobal) {
      for (int c = 0; c < info.components; ++c) out.push_back(values(c, 0));
    } else if (point) {
      Eigen::MatrixXd at(info.components, 1);
      point->Apply(values, at);
      for (int c = 0; c < info.components; ++c) out.push_back(at(c, 0));
    } else {
      for (int c = 0; c < info.components; ++c) {
        double acc = reduce == Reduce::kMin   ? std::numeric_limits<double>::infinity()
                     : reduce == Reduce::kMax ? -std::numeric_limits<double>::infinity()
                                              : 0.0;
        for (int i : items) {
          double v = values(c, i);
          if (reduce == Reduce::kMin)
            acc = std::min(acc, v);
          else if (reduce == Reduce::kMax)
            acc = std::max(acc, v);
          else
            acc += v;
        }
        if (reduce == Reduce::kMean) acc /= static_cast<double>(items.size());
        out.push_back(acc);
      }
    }
  }
}

Probe ParseProbe(const std::string& name, const JsonNode& node, const Kernel& kernel) {
  node.CheckKeys(
      {"object", "point", "region", "fields", "field", "reduce", "every", "description"});
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
  std::vector<std::string> names;
  if (auto f = node.Find("field")) names.push_back(f->AsString());
  if (auto f = node.Find("fields")) {
    auto more = f->AsStrings();
    names.insert(names.end(), more.begin(), more.end());
  }
  if (names.empty()) node.Fail("missing required key 'fields'");
  if (node.Has("point") && node.Has("region")) node.Fail("give either 'point' or 'region'");
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
    const Mesh& mesh = object.domain();
    Points target = p->AsVec3();
    probe.point = object.MapFromNodes(target);
    const double diag = (mesh.nodes.rowwise().maxCoeff() - mesh.nodes.rowwise().minCoeff()).norm();
    if (probe.point->max_distance() > 1e-6 * diag)
      p->Fail(fmt::format("the point lies {:.4g} outside the domain of '{}'",
                          probe.point->max_distance(), object.name()));
  } else if (auto r = node.Find("region")) {
    probe.region = true;
    Region region = ParseRegion(*r);
    try {
      if (location == FieldLocation::kNode)
        probe.items = SelectNodes(region, object.domain());
      else if (location == FieldLocation::kBoundaryVertex)
        probe.items = SelectBoundaryVertices(region, object.domain(), object.boundary());
      else
        r->Fail("region probes reduce node or boundary-vertex fields");
    } catch (const InputError& e) {
      r->Fail(e.what());
    }
    if (probe.items.empty()) r->Fail("the region selects nothing");
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
                             bool resume) {
  std::filesystem::create_directories(directory);
  for (auto& probe : probes) {
    auto path = directory / (probe.name + ".csv");
    Stream stream{std::move(probe), {}, 0, path};
    stream.file.open(path, resume ? std::ios::app : std::ios::out | std::ios::trunc);
    if (!stream.file)
      throw std::runtime_error(fmt::format("{}: cannot create file", path.string()));
    if (!resume) stream.file << stream.probe.Header() << '\n';
    stream.file.precision(17);
    streams_.push_back(std::move(stream));
  }
}

void ProbeRecorder::Observe(const Kernel& kernel, double t) {
  const double tolerance = 1e-9 * kernel.macro_dt();
  for (auto& s : streams_) {
    if (t + tolerance < s.next) continue;
    s.probe.Sample(row_);
    s.file << t;
    for (double v : row_) s.file << ',' << v;
    s.file << '\n';
    s.file.flush();
    if (!s.file) throw std::runtime_error(fmt::format("probe '{}': write failed", s.probe.name));
    if (s.probe.every > 0)
      while (s.next <= t + tolerance) s.next += s.probe.every;
  }
}

void ProbeRecorder::Finish(const Kernel& /*kernel*/) {
  for (auto& s : streams_) s.file.flush();
}

}  // namespace gipsi
