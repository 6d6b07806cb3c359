#pragma once
/// @file
/// `CsvTable`: a numeric CSV file with a header row, as the probes write them (`time` then one
/// column per field component), read back for plotting.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// Columns of numbers by name. Copyable and movable.
struct CsvTable {
  std::string file;                          ///< where it was read from (for messages)
  std::vector<std::string> names;            ///< header, in file order
  std::vector<std::vector<double>> columns;  ///< columns[c][row]

  [[nodiscard]] std::size_t num_rows() const { return columns.empty() ? 0 : columns[0].size(); }
  /// Index of the column called `name`, or -1.
  [[nodiscard]] int Find(std::string_view name) const;
  /// The column called `name`; throws InputError naming the file and listing the columns.
  [[nodiscard]] const std::vector<double>& Column(std::string_view name) const;
};

/// Reads a comma-separated file whose first line names the columns and whose other lines hold
/// numbers ("nan" and "inf" accepted; blank lines skipped). Throws InputError naming the file,
/// the line and the column for a missing file, an empty header, a wrong number of fields or
/// something that is not a number.
CsvTable ReadCsv(const std::filesystem::path& file);

}  // namespace gipsi::viz
GIPSI_EXPORT_END
