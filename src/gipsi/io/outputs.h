#pragma once
/// @file
/// Result writers attached to a scene's kernel: VTU/PVD time series of every (leaf) object's
/// domain with its node and element fields, of embedded display surfaces, and probe CSVs.
///
/// Layout of an output directory:
///   <out>/<object>.pvd                 ParaView collection (open this one)
///   <out>/<object>/<object>_NNNNNN.vtu one frame per output time (a distributed object:
///                                      <object>_NNNNNN.pvtu and one _p<rank>.vtu per rank)
///   <out>/<object>_display.pvd, <out>/<object>_display/...   display surface (if embedded)
///   <out>/probes/<probe>.csv           one row per sample: time, values

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/kernel.h"
#include "gipsi/io/scene.h"
#include "gipsi/io/vtu_writer.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Whether the outputs attached in this process write their files. Every rank of a distributed
/// run (gipsi/parallel/) attaches the scene's outputs and samples the probes at the same times,
/// because a distributed object's reads are collective; only rank 0 writes (kWrite), the others
/// (kReadOnly) write nothing but their own piece of each distributed object's VTU frames
/// (SimObject::output_piece).
enum class OutputFiles { kWrite, kReadOnly };

/// Writes VTU frames and keeps the PVD collections current after every frame, so a run that
/// stops early leaves a valid series up to its last frame.
class VtuSeriesWriter final : public Observer {
 public:
  /// Creates `directory` and one collection per object; throws std::exception on I/O errors.
  /// With `resume`, existing collections are left untouched until CommitRestore. A distributed
  /// object (SimObject::output_piece) is written as one `.vtu` piece per rank, by each rank, in
  /// `<object>/<object>_NNNNNN_p<rank>.vtu`, joined by `<object>_NNNNNN.pvtu`, which the `.pvd`
  /// lists. With OutputFiles::kReadOnly only those pieces are written.
  VtuSeriesWriter(std::vector<const SimObject*> objects, const std::filesystem::path& directory,
                  double every, bool display, bool resume = false,
                  OutputFiles files = OutputFiles::kWrite);
  void Observe(const Kernel& kernel, double t) override;
  /// Checkpoints: next output time, frame number and the frames of every collection
  /// (RestoreState only reads and checks them; CommitRestore rewrites the collections).
  void SaveState(StateWriter& out) override;
  void RestoreState(StateReader& in) override;
  void CommitRestore() override;

 private:
  struct Series {
    const SimObject* object;
    PvdWriter domain;
    std::unique_ptr<PvdWriter> display;
  };
  void WriteFrame(Series& series, double t);

  std::filesystem::path directory_;
  double every_;
  bool write_ = true;
  double next_ = 0;
  std::int64_t frame_ = 0;
  std::vector<double> frame_times_;  // of every frame so far (all series share them)
  std::vector<Series> series_;
};

/// What a run of a scene from t = 0 to its end time will write, estimated before it starts.
/// Plain struct.
struct OutputEstimate {
  std::int64_t vtu_frames = 0;       ///< frames of every VTU series
  std::uintmax_t vtu_bytes = 0;      ///< all VTU files and PVD collections (exact for the frames)
  std::uintmax_t probe_bytes = 0;    ///< all probe CSVs (an upper bound: 25 bytes per number)
  std::string largest_series;        ///< the object whose series is largest ("" if none)
  std::uintmax_t largest_frame = 0;  ///< bytes of one frame of that series
  [[nodiscard]] std::uintmax_t total() const { return vtu_bytes + probe_bytes; }
};

/// Estimates the files AttachOutputs would make a run write: the VTU frames' sizes are exact
/// (VtuFileBytes), their number the output times up to `scene.end_time`; probe rows are
/// counted the same way with a bound on each number's width.
OutputEstimate EstimateOutputs(const Scene& scene);

/// Attaches the scene's outputs (VTU series if enabled, probe CSVs) to its kernel, writing under
/// `directory`. Throws InputError, naming the scene key that drives it, if EstimateOutputs
/// exceeds `scene.limits.max_output_bytes`; nothing is created then. Throws std::exception if
/// the directory or files cannot be created. With
/// `resume`, no existing file is changed until the kernel has read and checked the whole
/// checkpoint (Kernel::RestoreState); then every file is cut back to its state at the
/// checkpoint. A refused checkpoint leaves the outputs as they were. With
/// OutputFiles::kReadOnly (the ranks of a distributed run but the first) the outputs sample
/// their fields as usual and create or write no file.
void AttachOutputs(Scene& scene, const std::filesystem::path& directory, bool resume = false,
                   OutputFiles files = OutputFiles::kWrite);

}  // namespace gipsi
GIPSI_EXPORT_END
