#include "gipsi/io/outputs.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"

#include "gipsi/base/state.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/io/sample_times.h"

namespace gipsi {

VtuSeriesWriter::VtuSeriesWriter(std::vector<const SimObject*> objects,
                                 const std::filesystem::path& directory, double every, bool display,
                                 bool resume, OutputFiles files)
    : directory_(directory), every_(every), write_(files == OutputFiles::kWrite) {
  if (write_) std::filesystem::create_directories(directory);
  for (const SimObject* object : objects) {
    const Mesh& mesh = object->domain();
    if (mesh.num_tets() == 0 && mesh.num_triangles() == 0 &&
        object->boundary().num_triangles() == 0)
      continue;  // nothing drawable (a point object)
    // A distributed object's pieces are written by every rank (output_piece).
    if (write_ || object->output_piece().count > 1)
      std::filesystem::create_directories(directory / object->name());
    Series series{object, PvdWriter(directory / (object->name() + ".pvd"), write_ && !resume),
                  nullptr};
    if (display && object->display().map) {
      if (write_) std::filesystem::create_directories(directory / (object->name() + "_display"));
      series.display = std::make_unique<PvdWriter>(directory / (object->name() + "_display.pvd"),
                                                   write_ && !resume);
    }
    series_.push_back(std::move(series));
  }
}

namespace {

/// A frame of an object on 10-node tets: its nodes, then its edge nodes, with each node field
/// extended to the edge nodes (the object's own values, or the mean of the edge's ends).
void WriteQuadraticFrame(const SimObject& object, const SimObject::QuadraticOutput& quadratic,
                         const std::vector<FieldId>& point_ids, VtuFields& fields,
                         const std::filesystem::path& path) {
  const Index n = object.domain_positions().cols();
  const Index k = quadratic.edge_positions.cols();
  Points nodes(3, n + k);
  nodes << object.domain_positions(), quadratic.edge_positions;
  for (std::size_t f = 0; f < point_ids.size(); ++f) {
    Eigen::MatrixXd& values = fields.point_data[f].values;
    values.conservativeResize(Eigen::NoChange, n + k);
    if (object.ReadEdgeNodeField(point_ids[f], values.rightCols(k))) continue;
    for (Index e = 0; e < k; ++e)
      values.col(n + e) =
          0.5 * (values.col(quadratic.edge_ends(0, e)) + values.col(quadratic.edge_ends(1, e)));
  }
  WriteQuadraticVtu(path, nodes, quadratic.tets, fields);
}

}  // namespace

void VtuSeriesWriter::WriteFrame(Series& series, double t) {
  // A distributed object: this rank's part, one piece of the frame (output_piece).
  const SimObject::OutputPiece piece = series.object->output_piece();
  if (piece.count == 1 && !write_) return;  // whole objects: written by the first rank alone
  const SimObject& object = *piece.object;
  const Mesh& mesh = object.domain();
  VtuFields fields;
  std::vector<FieldId> point_ids;
  for (std::size_t f = 0; f < object.fields().size(); ++f) {
    const FieldInfo& info = object.fields()[f];
    if (!info.readable()) continue;
    if (info.location != FieldLocation::kNode && info.location != FieldLocation::kElement) continue;
    FieldId id(static_cast<std::int64_t>(f));
    NamedArray array{info.name, info.components,
                     Eigen::MatrixXd(info.components, object.FieldCount(id))};
    object.ReadField(id, array.values);
    if (info.location == FieldLocation::kNode) point_ids.push_back(id);
    (info.location == FieldLocation::kNode ? fields.point_data : fields.cell_data)
        .push_back(std::move(array));
  }
  if (piece.count > 1) {
    // Every rank writes its piece; the first also the .pvtu that joins them and the .pvd.
    const std::string name = series.object->name();
    const std::string stem = fmt::format("{}_{:06d}", name, frame_);
    WriteVtu(directory_ / name / fmt::format("{}_p{}.vtu", stem, piece.index),
             object.domain_positions(), mesh.tets, Triangles(3, 0), fields);
    if (!write_) return;
    std::vector<std::string> pieces;
    for (int k = 0; k < piece.count; ++k) pieces.push_back(fmt::format("{}_p{}.vtu", stem, k));
    std::vector<VtuArrayShape> point_shapes, cell_shapes;
    for (const NamedArray& a : fields.point_data) point_shapes.push_back({a.name, a.components});
    for (const NamedArray& a : fields.cell_data) cell_shapes.push_back({a.name, a.components});
    WritePvtu(directory_ / name / (stem + ".pvtu"), pieces, point_shapes, cell_shapes);
    // A run resumed on fewer ranks rewrites frames an earlier run wrote in more pieces: the
    // pieces past this count are no longer listed; nor is the frame a serial run wrote whole.
    for (int k = piece.count;; ++k) {
      std::error_code error;
      if (!std::filesystem::remove(directory_ / name / fmt::format("{}_p{}.vtu", stem, k), error))
        break;
    }
    std::error_code error;
    std::filesystem::remove(directory_ / name / (stem + ".vtu"), error);
    series.domain.AddFrame(t, name + "/" + stem + ".pvtu");
    return;
  }
  const std::string name = object.name();
  const std::string file = fmt::format("{}/{}_{:06d}.vtu", name, name, frame_);
  if (write_) {  // a distributed run's pieces of this frame are no longer listed
    const std::string stem = fmt::format("{}_{:06d}", name, frame_);
    std::error_code error;
    if (std::filesystem::remove(directory_ / name / (stem + ".pvtu"), error))
      for (int k = 0;
           std::filesystem::remove(directory_ / name / fmt::format("{}_p{}.vtu", stem, k), error);
           ++k) {
      }
  }
  SimObject::QuadraticOutput quadratic;
  if (mesh.num_tets() > 0 && object.GetQuadraticOutput(quadratic)) {
    WriteQuadraticFrame(object, quadratic, point_ids, fields, directory_ / file);
  } else if (mesh.num_tets() > 0) {
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
  if (every_ > 0) next_ = NextSampleTime(next_, every_, t + tolerance);
}

namespace {
/// The file a collection lists for a frame: a distributed object's frame is its `.pvtu`.
std::string FrameFile(const std::string& name, std::int64_t frame, bool display, bool pieces) {
  return display ? fmt::format("{}_display/{}_display_{:06d}.vtu", name, name, frame)
                 : fmt::format("{}/{}_{:06d}.{}", name, name, frame, pieces ? "pvtu" : "vtu");
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
  if (!write_) return;  // the collections are the first rank's
  for (Series& series : series_) {
    const bool pieces = series.object->output_piece().count > 1;
    std::vector<std::pair<double, std::string>> frames, display;
    for (std::int64_t k = 0; k < frame_; ++k) {
      const double t = frame_times_[static_cast<std::size_t>(k)];
      // A frame a run of the other kind wrote (a serial run's whole .vtu before a distributed
      // resume) keeps its file.
      std::string file = FrameFile(series.object->name(), k, false, pieces);
      const std::string other = FrameFile(series.object->name(), k, false, !pieces);
      std::error_code error;
      if (!std::filesystem::exists(directory_ / file, error) &&
          std::filesystem::exists(directory_ / other, error))
        file = other;
      frames.emplace_back(t, file);
      display.emplace_back(t, FrameFile(series.object->name(), k, true, false));
    }
    series.domain.SetFrames(frames);
    if (series.display) series.display->SetFrames(display);
  }
}

void ProbeRecorder::SaveState(StateWriter& out) {
  out.BeginSection("ProbeRecorder", 2);
  out.WriteInt(static_cast<std::int64_t>(streams_.size()));
  for (auto& s : streams_) {
    // A rank that does not write (OutputFiles::kReadOnly) has no file: length 0.
    std::int64_t length = 0;
    if (write_) {
      s.file.flush();
      length = static_cast<std::int64_t>(s.file.tellp());
      if (!s.file || length < 0)
        throw std::runtime_error(fmt::format("{}: cannot tell the file length", s.path.string()));
    }
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
    if (!write_) continue;  // the files are the first rank's to check and cut
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
  if (!write_) return;
  for (auto& s : streams_) {
    s.file.close();
    std::filesystem::resize_file(s.path, s.resume_length);
    s.file.open(s.path, std::ios::app);
    if (!s.file) throw std::runtime_error(fmt::format("{}: cannot reopen", s.path.string()));
    s.file.precision(17);
  }
}

namespace {

/// The leaf objects whose VTU series a scene writes.
std::vector<const SimObject*> VtuObjects(const Scene& scene) {
  const Kernel& kernel = *scene.kernel;
  std::vector<const SimObject*> leaves;
  if (scene.vtu.objects.empty()) {
    for (std::size_t i = 0; i < kernel.coordinator().num_objects(); ++i)
      kernel.coordinator().object(i).CollectLeaves(leaves);
  } else {
    for (const auto& name : scene.vtu.objects) kernel.FindObject(name).CollectLeaves(leaves);
  }
  return leaves;
}

/// Output times of a series sampled every `every` seconds (0: every macro step) over a run of
/// `steps` macro steps of `macro_dt`, the first at t = 0 — as the observers sample.
std::int64_t Samples(double every, double macro_dt, std::int64_t steps) {
  if (every <= macro_dt * (1 + 1e-9)) return steps + 1;
  const double end = static_cast<double>(steps) * macro_dt;
  return std::min(steps, static_cast<std::int64_t>(std::floor(end / every * (1 + 1e-12)))) + 1;
}

/// Bytes of one frame of `object`'s series (domain and, if written, display), as WriteFrame
/// writes it; 0 for an object without a series.
std::uintmax_t FrameBytes(const SimObject& object, bool display) {
  const Mesh& mesh = object.domain();
  std::vector<VtuArrayShape> point_data, cell_data;
  for (const FieldInfo& info : object.fields()) {
    if (!info.readable()) continue;
    if (info.location == FieldLocation::kNode)
      point_data.push_back({info.name, info.components});
    else if (info.location == FieldLocation::kElement)
      cell_data.push_back({info.name, info.components});
  }
  std::uintmax_t bytes = 0;
  SimObject::QuadraticOutput quadratic;
  const auto* split = dynamic_cast<const PartitionedObject*>(&object);
  if (split != nullptr && !split->holds_whole_domain() && mesh.num_tets() > 0) {
    // Its pieces: the whole mesh's nodes and tets (and the nodes the parts share once more).
    bytes =
        VtuFileBytes(split->whole_num_nodes(), split->whole_num_tets(), 0, point_data, cell_data);
  } else if (mesh.num_tets() > 0 && object.GetQuadraticOutput(quadratic)) {
    bytes =
        QuadraticVtuFileBytes(object.domain_positions().cols() + quadratic.edge_positions.cols(),
                              quadratic.tets.cols(), point_data, cell_data);
  } else if (mesh.num_tets() > 0 || mesh.num_triangles() > 0) {
    bytes = VtuFileBytes(object.domain_positions().cols(), mesh.num_tets(),
                         mesh.num_tets() > 0 ? 0 : mesh.num_triangles(), point_data, cell_data);
  } else if (object.boundary().num_triangles() > 0) {
    bytes = VtuFileBytes(object.boundary().num_vertices(), 0, object.boundary().num_triangles(), {},
                         {});
  } else {
    return 0;
  }
  if (display && object.display().map)
    bytes += VtuFileBytes(object.display().positions.cols(), 0, object.display().triangles.cols(),
                          {}, {});
  return bytes;
}

/// Human-readable bytes ("3.2 GB").
std::string Bytes(std::uintmax_t n) {
  const double x = static_cast<double>(n);
  if (x >= 1e9) return fmt::format("{:.3g} GB", x / 1e9);
  if (x >= 1e6) return fmt::format("{:.3g} MB", x / 1e6);
  if (x >= 1e3) return fmt::format("{:.3g} kB", x / 1e3);
  return fmt::format("{} bytes", n);
}

}  // namespace

OutputEstimate EstimateOutputs(const Scene& scene) {
  const Kernel& kernel = *scene.kernel;
  const double macro_dt = kernel.macro_dt();
  const auto steps = static_cast<std::int64_t>(std::llround(scene.end_time / macro_dt));
  OutputEstimate estimate;
  if (scene.vtu.enabled) {
    estimate.vtu_frames = Samples(scene.vtu.every, macro_dt, steps);
    const auto frames = static_cast<std::uintmax_t>(estimate.vtu_frames);
    for (const SimObject* object : VtuObjects(scene)) {
      const std::uintmax_t frame = FrameBytes(*object, scene.vtu.display);
      if (frame == 0) continue;
      // A frame's line in its collection(s): the frame's time and file name, about 100 bytes.
      const std::uintmax_t pvd = (scene.vtu.display && object->display().map ? 2 : 1) * 100;
      estimate.vtu_bytes += frames * (frame + pvd);
      if (frame > estimate.largest_frame) {
        estimate.largest_frame = frame;
        estimate.largest_series = object->name();
      }
    }
  }
  for (const Probe& probe : scene.probes) {
    const std::string header = probe.Header();
    const auto columns =
        static_cast<std::uintmax_t>(std::count(header.begin(), header.end(), ',')) + 1;
    std::uintmax_t rows = 0;
    if (probe.is_line())
      rows = static_cast<std::uintmax_t>(probe.line.cols()) *
             std::max<std::uintmax_t>(probe.at.size(), 1);
    else
      rows = static_cast<std::uintmax_t>(Samples(probe.every, macro_dt, steps));
    // %.17g of a double takes at most 24 characters ("-1.2345678901234567e-308"), plus a
    // separator.
    estimate.probe_bytes += header.size() + 1 + rows * 25 * columns;
  }
  return estimate;
}

void AttachOutputs(Scene& scene, const std::filesystem::path& directory, bool resume,
                   OutputFiles files) {
  Kernel& kernel = *scene.kernel;
  if (scene.limits.max_output_bytes > 0) {
    const OutputEstimate estimate = EstimateOutputs(scene);
    if (estimate.total() > scene.limits.max_output_bytes) {
      const bool vtu = estimate.vtu_bytes >= estimate.probe_bytes;
      ThrowInputError(
          scene.file.string(), vtu ? "outputs.vtu.every" : "probes",
          fmt::format(
              "the run would write about {} ({}), over the limit of {}: {}, shorten the run, or "
              "raise the limit with `gipsi run --max-output` if the scene is trusted",
              Bytes(estimate.total()),
              vtu ? fmt::format("{} VTU frames, {} per frame of '{}'", estimate.vtu_frames,
                                Bytes(estimate.largest_frame), estimate.largest_series)
                  : fmt::format("probe CSVs {}", Bytes(estimate.probe_bytes)),
              Bytes(scene.limits.max_output_bytes),
              vtu ? "write frames less often (outputs.vtu.every), fewer objects "
                    "(outputs.vtu.objects) or none (--no-vtu)"
                  : "sample the probes less often (probes.<name>.every)"));
    }
  }
  if (scene.vtu.enabled)
    kernel.AddObserver(std::make_unique<VtuSeriesWriter>(
        VtuObjects(scene), directory, scene.vtu.every, scene.vtu.display, resume, files));
  if (!scene.probes.empty())
    kernel.AddObserver(std::make_unique<ProbeRecorder>(scene.probes, directory / "probes", resume,
                                                       files == OutputFiles::kReadOnly));
}

}  // namespace gipsi
