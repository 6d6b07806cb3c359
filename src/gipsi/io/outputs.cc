#include "gipsi/io/outputs.h"

#include <fmt/format.h>

#include "gipsi/core/state.h"

namespace gipsi {

VtuSeriesWriter::VtuSeriesWriter(std::vector<const SimObject*> objects,
                                 const std::filesystem::path& directory, double every, bool display,
                                 bool resume)
    : directory_(directory), every_(every) {
  std::filesystem::create_directories(directory);
  for (const SimObject* object : objects) {
    const Mesh& mesh = object->domain();
    if (mesh.num_tets() == 0 && mesh.num_triangles() == 0 &&
        object->boundary().num_triangles() == 0)
      continue;  // nothing drawable (a point object)
    std::filesystem::create_directories(directory / object->name());
    Series series{object, PvdWriter(directory / (object->name() + ".pvd"), !resume), nullptr};
    if (display && object->display().map) {
      std::filesystem::create_directories(directory / (object->name() + "_display"));
      series.display =
          std::make_unique<PvdWriter>(directory / (object->name() + "_display.pvd"), !resume);
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
  frame_times_.push_back(t);
  if (every_ > 0) {
    while (next_ <= t + tolerance) next_ += every_;
  }
}

namespace {
std::string FrameFile(const std::string& name, std::int64_t frame, bool display) {
  return display ? fmt::format("{}_display/{}_display_{:06d}.vtu", name, name, frame)
                 : fmt::format("{}/{}_{:06d}.vtu", name, name, frame);
}
}  // namespace

void PvdWriter::SetFrames(const std::vector<std::pair<double, std::string>>& frames) {
  frames_.clear();
  for (const auto& [time, file] : frames) frames_.push_back({time, file});
  Rewrite();
}

void VtuSeriesWriter::SaveState(StateWriter& out) {
  out.BeginSection("VtuSeriesWriter", 1);
  out.WriteDouble(next_);
  out.WriteInt(frame_);
  out.WriteInt(static_cast<std::int64_t>(series_.size()));
  out.WriteArray(frame_times_);
  out.EndSection();
}

void VtuSeriesWriter::RestoreState(StateReader& in) {
  in.BeginSection("VtuSeriesWriter", 1);
  next_ = in.ReadDouble();
  frame_ = in.ReadInt();
  if (in.ReadInt() != static_cast<std::int64_t>(series_.size()))
    in.Fail("the checkpoint has VTU series of other objects");
  in.ReadArray(frame_times_);
  if (static_cast<std::int64_t>(frame_times_.size()) != frame_) in.Fail("corrupted VTU frames");
  in.EndSection();
}

void VtuSeriesWriter::CommitRestore() {
  for (Series& series : series_) {
    std::vector<std::pair<double, std::string>> frames, display;
    for (std::int64_t k = 0; k < frame_; ++k) {
      const double t = frame_times_[static_cast<std::size_t>(k)];
      frames.emplace_back(t, FrameFile(series.object->name(), k, false));
      display.emplace_back(t, FrameFile(series.object->name(), k, true));
    }
    series.domain.SetFrames(frames);
    if (series.display) series.display->SetFrames(display);
  }
}

void ProbeRecorder::SaveState(StateWriter& out) {
  out.BeginSection("ProbeRecorder", 2);
  out.WriteInt(static_cast<std::int64_t>(streams_.size()));
  for (auto& s : streams_) {
    s.file.flush();
    const auto length = static_cast<std::int64_t>(s.file.tellp());
    if (!s.file || length < 0)
      throw std::runtime_error(fmt::format("{}: cannot tell the file length", s.path.string()));
    out.WriteString(s.probe.name);
    out.WriteDouble(s.next);
    out.WriteInt(static_cast<std::int64_t>(s.next_at));
    out.WriteInt(length);
  }
  out.EndSection();
}

void ProbeRecorder::RestoreState(StateReader& in) {
  in.BeginSection("ProbeRecorder", 2);
  if (in.ReadInt() != static_cast<std::int64_t>(streams_.size()))
    in.Fail("the checkpoint has other probes");
  for (auto& s : streams_) {
    if (in.ReadString() != s.probe.name) in.Fail("the checkpoint has other probes");
    s.next = in.ReadDouble();
    s.next_at = static_cast<std::size_t>(in.ReadInt());
    const std::int64_t length = in.ReadInt();
    std::error_code error;
    const auto size = std::filesystem::file_size(s.path, error);
    if (error || length < 0 || static_cast<std::uintmax_t>(length) > size)
      in.Fail(
          fmt::format("{} is shorter than at the checkpoint ({} bytes); resume with the "
                      "output directory of the interrupted run",
                      s.path.string(), length));
    s.resume_length = static_cast<std::uintmax_t>(length);
  }
  in.EndSection();
}

void ProbeRecorder::CommitRestore() {
  for (auto& s : streams_) {
    s.file.close();
    std::filesystem::resize_file(s.path, s.resume_length);
    s.file.open(s.path, std::ios::app);
    if (!s.file) throw std::runtime_error(fmt::format("{}: cannot reopen", s.path.string()));
    s.file.precision(17);
  }
}

void AttachOutputs(Scene& scene, const std::filesystem::path& directory, bool resume) {
  Kernel& kernel = *scene.kernel;
  if (scene.vtu.enabled) {
    std::vector<const SimObject*> leaves;
    if (scene.vtu.objects.empty()) {
      for (std::size_t i = 0; i < kernel.coordinator().num_objects(); ++i)
        kernel.coordinator().object(i).CollectLeaves(leaves);
    } else {
      for (const auto& name : scene.vtu.objects) kernel.FindObject(name).CollectLeaves(leaves);
    }
    kernel.AddObserver(std::make_unique<VtuSeriesWriter>(
        std::move(leaves), directory, scene.vtu.every, scene.vtu.display, resume));
  }
  if (!scene.probes.empty())
    kernel.AddObserver(std::make_unique<ProbeRecorder>(scene.probes, directory / "probes", resume));
}

}  // namespace gipsi
