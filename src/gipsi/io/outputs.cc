#include "gipsi/io/outputs.h"

#include <fmt/format.h>

namespace gipsi {

VtuSeriesWriter::VtuSeriesWriter(std::vector<const SimObject*> objects,
                                 const std::filesystem::path& directory, double every, bool display)
    : directory_(directory), every_(every) {
  std::filesystem::create_directories(directory);
  for (const SimObject* object : objects) {
    const Mesh& mesh = object->domain();
    if (mesh.num_tets() == 0 && mesh.num_triangles() == 0 &&
        object->boundary().num_triangles() == 0)
      continue;  // nothing drawable (a point object)
    std::filesystem::create_directories(directory / object->name());
    Series series{object, PvdWriter(directory / (object->name() + ".pvd")), nullptr};
    if (display && object->display().map) {
      std::filesystem::create_directories(directory / (object->name() + "_display"));
      series.display = std::make_unique<PvdWriter>(directory / (object->name() + "_display.pvd"));
    }
    series_.push_back(std::move(series));
  }
}

void VtuSeriesWriter::WriteFrame(Series& series, double t) {
  const SimObject& object = *series.object;
  const Mesh& mesh = object.domain();
  VtuFields fields;
  for (std::size_t f = 0; f < object.fields().size(); ++f) {
    const FieldInfo& info = object.fields()[f];
    if (!info.readable()) continue;
    if (info.location != FieldLocation::kNode && info.location != FieldLocation::kElement) continue;
    FieldId id(static_cast<std::int64_t>(f));
    NamedArray array{info.name, info.components,
                     Eigen::MatrixXd(info.components, object.FieldCount(id))};
    object.ReadField(id, array.values);
    (info.location == FieldLocation::kNode ? fields.point_data : fields.cell_data)
        .push_back(std::move(array));
  }
  const std::string name = object.name();
  const std::string file = fmt::format("{}/{}_{:06d}.vtu", name, name, frame_);
  if (mesh.num_tets() > 0) {
    WriteVtu(directory_ / file, object.domain_positions(), mesh.tets, Triangles(3, 0), fields);
  } else if (mesh.num_triangles() > 0) {
    WriteVtu(directory_ / file, object.domain_positions(), Tets(4, 0), mesh.triangles, fields);
  } else {
    // A spring network or other element-free domain: draw its boundary triangles, if any.
    Points boundary_positions;
    object.boundary().Gather(object.domain_positions(), boundary_positions);
    WriteVtu(directory_ / file, boundary_positions, Tets(4, 0), object.boundary().triangles);
  }
  series.domain.AddFrame(t, file);
  if (series.display) {
    const std::string display_file =
        fmt::format("{}_display/{}_display_{:06d}.vtu", name, name, frame_);
    WriteVtu(directory_ / display_file, object.display().positions, Tets(4, 0),
             object.display().triangles);
    series.display->AddFrame(t, display_file);
  }
}

void VtuSeriesWriter::Observe(const Kernel& kernel, double t) {
  const double tolerance = 1e-9 * kernel.macro_dt();
  if (t + tolerance < next_) return;
  for (Series& series : series_) {
    series.object->UpdateDisplay();
    WriteFrame(series, t);
  }
  ++frame_;
  if (every_ > 0) {
    while (next_ <= t + tolerance) next_ += every_;
  }
}

void AttachOutputs(Scene& scene, const std::filesystem::path& directory) {
  Kernel& kernel = *scene.kernel;
  if (scene.vtu.enabled) {
    std::vector<const SimObject*> leaves;
    if (scene.vtu.objects.empty()) {
      for (std::size_t i = 0; i < kernel.coordinator().num_objects(); ++i)
        kernel.coordinator().object(i).CollectLeaves(leaves);
    } else {
      for (const auto& name : scene.vtu.objects) kernel.FindObject(name).CollectLeaves(leaves);
    }
    kernel.AddObserver(std::make_unique<VtuSeriesWriter>(std::move(leaves), directory,
                                                         scene.vtu.every, scene.vtu.display));
  }
  if (!scene.probes.empty())
    kernel.AddObserver(std::make_unique<ProbeRecorder>(scene.probes, directory / "probes"));
}

}  // namespace gipsi
