#pragma once
/// @file
/// Writers for ParaView output: VTK XML unstructured grids (`.vtu`) with point and cell data, and
/// `.pvd` collections that index them by time.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// A named data array attached to points or cells: `values` is `components` by count (column j
/// holds the tuple of point or cell j). Plain data: copyable and movable.
struct NamedArray {
  std::string name;
  int components = 1;
  Eigen::MatrixXd values;
};

/// Point and cell data written with a `.vtu`. Point arrays have one column per node; cell arrays
/// one column per cell, tets first then triangles (the order `WriteVtu` writes cells in).
struct VtuFields {
  std::vector<NamedArray> point_data;
  std::vector<NamedArray> cell_data;
};

/// Writes an unstructured grid: `nodes` (3 by N), the tets (4 by E, VTK type 10) followed by the
/// triangles (3 by T, VTK type 5), and `fields`. All arrays are inline base64 binary without
/// compression (`header_type="UInt64"`): coordinates and data Float64, connectivity and offsets
/// Int64, types UInt8 — readable by ParaView/VTK and by `ReadVtu`, bit-exact.
///
/// Preconditions (checked, abort on violation): connectivity indices in [0, N); for each array,
/// `values.rows() == components >= 1` and `values.cols()` is N (point data) or E+T (cell data).
/// Throws InputError if the file cannot be written.
void WriteVtu(const std::filesystem::path& path, const Points& nodes, const Tets& tets,
              const Triangles& triangles, const VtuFields& fields = {});

/// Node indices of 10-node tets, one column per cell: the four vertices, then the middle nodes
/// of the edges (0,1), (1,2), (0,2), (0,3), (1,3), (2,3) (VTK_QUADRATIC_TETRA's order).
using QuadraticTetCells = Eigen::Matrix<int, 10, Eigen::Dynamic>;

/// Writes 10-node tets as VTK_QUADRATIC_TETRA cells (type 24; ParaView draws them curved and
/// subdivides them for its filters), like WriteVtu otherwise.
void WriteQuadraticVtu(const std::filesystem::path& path, const Points& nodes,
                       const QuadraticTetCells& tets, const VtuFields& fields = {});

/// Name and number of components of a data array, for sizing a `.vtu` before writing it.
struct VtuArrayShape {
  std::string name;
  int components = 1;
};

/// The exact size in bytes of the file `WriteVtu` writes for a grid of `num_nodes` nodes,
/// `num_tets` tets and `num_triangles` triangles with these point and cell arrays (their values
/// do not change the size: the encoding is uncompressed). Used to refuse output that would not
/// fit before a run starts (outputs.h).
std::uintmax_t VtuFileBytes(Index num_nodes, Index num_tets, Index num_triangles,
                            const std::vector<VtuArrayShape>& point_data,
                            const std::vector<VtuArrayShape>& cell_data);

/// The same for WriteQuadraticVtu's file of `num_tets` 10-node tets.
std::uintmax_t QuadraticVtuFileBytes(Index num_nodes, Index num_tets,
                                     const std::vector<VtuArrayShape>& point_data,
                                     const std::vector<VtuArrayShape>& cell_data);

/// Writes a parallel unstructured grid (`.pvtu`): the index of `pieces` (`.vtu` paths relative
/// to the `.pvtu`'s folder, as ParaView resolves them), each written by WriteVtu with these
/// point and cell arrays (all Float64), which ParaView opens as one dataset. Throws InputError
/// if the file cannot be written.
void WritePvtu(const std::filesystem::path& path, const std::vector<std::string>& pieces,
               const std::vector<VtuArrayShape>& point_data,
               const std::vector<VtuArrayShape>& cell_data);

/// `WriteVtu(path, mesh.nodes, mesh.tets, mesh.triangles, fields)`.
void WriteVtu(const std::filesystem::path& path, const Mesh& mesh, const VtuFields& fields = {});

/// Maintains a ParaView `.pvd` collection: a list of (time, file) frames, complete and valid on
/// disk after every added frame. The file is first written whole (a temporary file renamed over
/// the old one); each later frame is then written in place over the closing tags, as its
/// `<DataSet>` line followed by the closing tags again, in one write: a frame costs its own
/// bytes, not the whole collection's (rewriting it would write O(frames²) bytes in a long run),
/// and a killed process leaves the file as it was before or after that write. If the file is
/// not as this writer left it (changed or removed by someone else), or the write fails part
/// way (the old closing tags are then put back), the collection is written whole instead.
/// Movable, not copyable (it stands for one file).
class PvdWriter {
 public:
  /// Starts a collection at `path` and writes it (empty) if `write`; otherwise the file is left
  /// as it is until the first AddFrame or SetFrames (a series resumed from a checkpoint).
  /// Throws InputError if it cannot be written.
  explicit PvdWriter(std::filesystem::path path, bool write = true);

  PvdWriter(const PvdWriter&) = delete;
  PvdWriter& operator=(const PvdWriter&) = delete;
  PvdWriter(PvdWriter&&) = default;
  PvdWriter& operator=(PvdWriter&&) = default;

  /// Adds a frame at simulation time `time` (seconds) stored in `file` (a path relative to the
  /// `.pvd`'s folder, as ParaView resolves it), then rewrites the collection. Throws InputError
  /// if the collection cannot be written.
  void AddFrame(double time, const std::string& file);

  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  [[nodiscard]] std::size_t num_frames() const { return frames_.size(); }
  /// Replaces the frames (time, file) and rewrites the collection: a series resumed from a
  /// checkpoint (defined in outputs.cc).
  void SetFrames(const std::vector<std::pair<double, std::string>>& frames);

 private:
  struct Frame {
    double time;
    std::string file;
  };
  void Rewrite();
  /// Writes the last frame over the closing tags; false if the file is not as Rewrite or the
  /// previous Append left it, or the write failed (the file is then as before).
  bool Append();

  std::filesystem::path path_;
  std::vector<Frame> frames_;
  std::uintmax_t tail_ = 0;  ///< offset of the closing tags in the file
  bool written_ = false;     ///< whether tail_ describes the file on disk
};

}  // namespace gipsi
GIPSI_EXPORT_END
