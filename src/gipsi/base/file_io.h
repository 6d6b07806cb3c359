#pragma once
/// @file
/// Reading input files with limits, and writing output files atomically. Failures to write
/// outputs (a full disk, a read-only folder) are OutputError, kept apart from InputError: the
/// `gipsi` tool exits 4 for them and 1 for bad input.

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Writing an output failed. The message names the file and the system's reason (errno text),
/// e.g. `out/sheet/sheet_000003.vtu: cannot write: No space left on device`. Copyable.
class OutputError : public std::runtime_error {
 public:
  explicit OutputError(const std::string& message) : std::runtime_error(message) {}
};

/// Writes `bytes` to `path` atomically: into `path` + ".tmp" (created or truncated, written,
/// closed, each step checked), then renamed over `path`. A reader, or a run killed at any moment,
/// sees the old file or the whole new one, never a part. (No fsync: it would cost every VTU frame
/// a disk flush; checkpoints add their own.) On any failure the temporary file is removed and
/// OutputError is thrown naming `path`, the step and the errno text.
void WriteFileAtomically(const std::filesystem::path& path, std::string_view bytes);

/// Reads the whole regular file at `path`, of at most `max_bytes`. Throws InputError naming the
/// file and the reason, with `kind` ("scene file", "mesh file") saying what was expected: it
/// cannot be opened (errno text), is a directory, is not a regular file (a device such as
/// /dev/zero, a pipe, a socket: their reads need not end), or is larger than `max_bytes`.
std::string ReadRegularFile(const std::filesystem::path& path, std::uintmax_t max_bytes,
                            std::string_view kind);

/// A std::filesystem error as `PATH: WHAT: REASON` (e.g. `out/x: cannot create directories:
/// Permission denied`) instead of its raw `filesystem error: ...: ... [PATH]`.
std::string DescribeFilesystemError(const std::filesystem::filesystem_error& e);

}  // namespace gipsi
GIPSI_EXPORT_END
