#pragma once
/// @file
/// Object state for checkpoints and roll-back: a small typed binary format.
///
/// A `StateWriter` appends typed entries (doubles, integers, strings, arrays, Eigen matrices)
/// grouped in tagged, versioned sections ("MassSpring" v1, ...); a `StateReader` reads them back
/// in the same order and checks every type code, section tag, version and array shape, so a
/// checkpoint from another scene or build throws an InputError naming the section and what
/// differs instead of restoring garbage. Values are stored bit for bit (native byte order), so a
/// restored state continues bitwise identically.
///
/// Checkpoint files (`WriteCheckpointFile`) wrap the bytes in a header with a magic string, the
/// payload size and an FNV-1a hash, written atomically: a temporary file in the same directory,
/// fsync, rename, fsync of the directory. A truncated or corrupted file is refused.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Appends typed entries to a byte buffer. Copyable and movable.
class StateWriter {
 public:
  /// Opens a section: everything until the matching EndSection belongs to `tag` (e.g. the
  /// object type) at format `version`.
  void BeginSection(std::string_view tag, std::uint32_t version);
  void EndSection();

  void WriteDouble(double x);
  void WriteInt(std::int64_t x);
  void WriteBool(bool x) { WriteInt(x ? 1 : 0); }
  void WriteString(std::string_view s);
  /// An array of a trivially copyable element type (double, int, std::uint8_t, ...).
  template <class T>
  void WriteArray(std::span<const T> values) {
    static_assert(std::is_trivially_copyable_v<T>);
    WriteArrayBytes(sizeof(T), values.size(), values.data());
  }
  template <class T>
  void WriteArray(const std::vector<T>& values) {
    WriteArray(std::span<const T>(values));
  }
  /// A dense matrix or vector (rows, columns, column-major values).
  template <class Derived>
  void WriteMatrix(const Eigen::DenseBase<Derived>& m) {
    using Scalar = typename Derived::Scalar;
    const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> plain = m;
    WriteMatrixBytes(sizeof(Scalar), plain.rows(), plain.cols(), plain.data());
  }

  /// The bytes written so far (all sections must be closed to read them back).
  [[nodiscard]] const std::string& bytes() const { return bytes_; }
  [[nodiscard]] std::string TakeBytes() { return std::move(bytes_); }

 private:
  void WriteArrayBytes(std::size_t element_size, std::size_t count, const void* data);
  void WriteMatrixBytes(std::size_t element_size, Index rows, Index cols, const void* data);
  void Raw(const void* data, std::size_t size);

  std::string bytes_;
  std::vector<std::size_t> open_;  // offsets of the open sections' length fields
};

/// Reads what a StateWriter wrote, checking types, tags, versions and shapes. Every mismatch
/// throws InputError("<source>: <section path>: ..."). Not copyable; movable.
class StateReader {
 public:
  /// `source` names the data in messages (e.g. the checkpoint file).
  StateReader(std::string bytes, std::string source);

  /// Enters the next section, which must be `tag` at `version`.
  void BeginSection(std::string_view tag, std::uint32_t version);
  /// Leaves the section; throws if it has unread entries.
  void EndSection();

  [[nodiscard]] double ReadDouble();
  [[nodiscard]] std::int64_t ReadInt();
  [[nodiscard]] bool ReadBool() { return ReadInt() != 0; }
  [[nodiscard]] std::string ReadString();
  /// Reads an array into `out`, resizing it.
  template <class T>
  void ReadArray(std::vector<T>& out) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t count = ReadArrayHeader(sizeof(T));
    out.resize(count);
    ReadBytes(out.data(), count * sizeof(T));
  }
  /// Reads an array that must have exactly `out.size()` entries (`what` names it in messages).
  template <class T>
  void ReadArrayExact(std::vector<T>& out, std::string_view what) {
    static_assert(std::is_trivially_copyable_v<T>);
    const std::size_t count = ReadArrayHeader(sizeof(T));
    if (count != out.size()) ShapeError(what, out.size(), 1, count, 1);
    ReadBytes(out.data(), count * sizeof(T));
  }
  /// Reads a matrix into `m`, resizing it (for history that may be empty).
  template <class M>
  void ReadMatrix(M& m) {
    const auto [rows, cols] = ReadMatrixHeader(sizeof(typename M::Scalar));
    m.resize(rows, cols);
    ReadBytes(m.data(), static_cast<std::size_t>(rows * cols) * sizeof(typename M::Scalar));
  }
  /// Reads a matrix that must have `m`'s current shape (state arrays sized by the scene).
  template <class M>
  void ReadMatrixExact(M& m, std::string_view what) {
    const auto [rows, cols] = ReadMatrixHeader(sizeof(typename M::Scalar));
    if (rows != m.rows() || cols != m.cols())
      ShapeError(what, static_cast<std::size_t>(m.rows()), static_cast<std::size_t>(m.cols()),
                 static_cast<std::size_t>(rows), static_cast<std::size_t>(cols));
    ReadBytes(m.data(), static_cast<std::size_t>(rows * cols) * sizeof(typename M::Scalar));
  }

  /// What the data is named by in messages (e.g. the checkpoint file).
  [[nodiscard]] const std::string& source() const { return source_; }
  /// True when everything has been read.
  [[nodiscard]] bool at_end() const { return pos_ == bytes_.size(); }
  /// Skips the rest of the open section (the next call is its EndSection).
  void SkipRestOfSection();
  /// Whether the next entry is a section tagged `tag` (reads nothing).
  [[nodiscard]] bool NextIsSection(std::string_view tag) const;
  /// Skips the next `count` entries of the open section (or of the top level).
  void SkipEntries(int count) {
    for (int i = 0; i < count; ++i) SkipEntry();
  }

  /// Where the reader is, as entries rather than bytes: the sections it is in (by their index
  /// among their parent's entries, their tag and version) and how many entries of the innermost
  /// it has read. Data written by the same code for another share of a problem (another MPI
  /// rank's checkpoint, whose arrays have other lengths) has the same entries up to a point
  /// where the shares differ in content only: Seek finds that point there. Plain struct.
  struct Position {
    std::vector<std::uint64_t> index;  ///< per open section, then the entries read in the last
    std::vector<std::string> tags;
    std::vector<std::uint32_t> versions;
  };
  [[nodiscard]] Position position() const;
  /// From the start of the data (nothing read yet): skips to `at`, entering its sections (each
  /// checked like BeginSection: a data of another layout throws InputError).
  void Seek(const Position& at);
  /// Throws InputError(source: section path: what).
  [[noreturn]] void Fail(std::string_view what) const;

 private:
  std::size_t ReadArrayHeader(std::size_t element_size);
  std::pair<Index, Index> ReadMatrixHeader(std::size_t element_size);
  [[noreturn]] void ShapeError(std::string_view what, std::size_t rows, std::size_t cols,
                               std::size_t got_rows, std::size_t got_cols) const;
  void Expect(char code, std::string_view what);
  // Skips one entry of any kind.
  void SkipEntry();
  // Skips `size` bytes of the current section.
  void SkipBytes(std::uint64_t size);
  void ReadBytes(void* out, std::size_t size);
  std::uint64_t ReadU64();

  std::string bytes_;
  std::string source_;
  std::size_t pos_ = 0;
  struct Open {
    std::string tag;
    std::size_t end;
    std::uint32_t version = 0;
    std::uint64_t entries = 0;  // read in this section so far
  };
  std::vector<Open> open_;
  std::uint64_t top_entries_ = 0;  // read outside every section so far
};

/// A new process-wide stamp, never 0 (thread-safe): marks the contents of a rarely written
/// state field (Stamped in state_value.h, BoundaryConditions::Applied), so that equal stamps
/// mean equal contents.
[[nodiscard]] std::uint64_t NewStateStamp();

/// Writes `payload` to `path` atomically and durably (temporary file `<path>.tmp`, fsync,
/// rename, fsync of the directory), so a crash at any moment leaves either the previous file or
/// the new one. Throws std::runtime_error naming the file on I/O errors.
void WriteCheckpointFile(const std::filesystem::path& path, std::string_view payload);
/// Reads and verifies a file written by WriteCheckpointFile; throws InputError naming the file
/// if it is missing, not a checkpoint, truncated or corrupted.
[[nodiscard]] std::string ReadCheckpointFile(const std::filesystem::path& path);

}  // namespace gipsi
GIPSI_EXPORT_END
