#include "gipsi/viz/csv_table.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"
#include "gipsi/base/json_node.h"

namespace gipsi::viz {
namespace {

std::vector<std::string_view> Split(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    std::string_view field = line.substr(start, comma - start);
    while (!field.empty() && (field.front() == ' ' || field.front() == '\t'))
      field.remove_prefix(1);
    while (!field.empty() && (field.back() == ' ' || field.back() == '\t' || field.back() == '\r'))
      field.remove_suffix(1);
    fields.push_back(field);
    if (comma == std::string_view::npos) return fields;
    start = comma + 1;
  }
}

bool ParseNumber(std::string_view text, double& value) {
  if (text == "nan" || text == "-nan" || text == "NaN") {
    value = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  if (text == "inf" || text == "-inf") {
    value = text[0] == '-' ? -std::numeric_limits<double>::infinity()
                           : std::numeric_limits<double>::infinity();
    return true;
  }
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc() && end == text.data() + text.size() && !text.empty();
}

}  // namespace

int CsvTable::Find(std::string_view name) const {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  return -1;
}

const std::vector<double>& CsvTable::Column(std::string_view name) const {
  const int i = Find(name);
  if (i < 0)
    ThrowInputError(file, "",
                    fmt::format("no column '{}'{}; the columns are: {}", name,
                                SuggestClosest(name, names), fmt::join(names, ", ")));
  return columns[std::size_t(i)];
}

CsvTable ReadCsv(const std::filesystem::path& file) {
  CsvTable table;
  table.file = file.string();
  std::ifstream in(file);
  if (!in) ThrowInputError(table.file, "", "cannot open the CSV file for reading");
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const auto fields = Split(line);
    const std::string where = fmt::format("line {}", number);
    if (table.names.empty()) {
      for (auto f : fields) {
        if (f.empty()) ThrowInputError(table.file, where, "expected a header of column names");
        table.names.emplace_back(f);
      }
      table.columns.resize(table.names.size());
      continue;
    }
    if (fields.size() != table.names.size())
      ThrowInputError(table.file, where,
                      fmt::format("expected {} comma-separated values (one per column of the "
                                  "header), got {}",
                                  table.names.size(), fields.size()));
    for (std::size_t c = 0; c < fields.size(); ++c) {
      double value = 0;
      if (!ParseNumber(fields[c], value))
        ThrowInputError(
            table.file, where,
            fmt::format("column '{}': expected a number, got '{}'", table.names[c], fields[c]));
      table.columns[c].push_back(value);
    }
  }
  if (table.names.empty()) ThrowInputError(table.file, "", "empty file: expected a header line");
  return table;
}

}  // namespace gipsi::viz
