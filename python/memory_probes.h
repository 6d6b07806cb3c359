#pragma once
/// @file
/// The Python module's in-memory probe recorder (`Simulation.probes`).

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/state.h"
#include "gipsi/core/kernel.h"
#include "gipsi/io/probes.h"
#include "gipsi/io/sample_times.h"

namespace gipsi::python {

namespace py = pybind11;

/// Records the scene's probes in memory, at the times their CSVs would get rows
/// (io/probes.cc): point and region probes every `every` on the grid NextSampleTime keeps;
/// line probes at their `at` times, or once at the end of the first run() when they have none.
/// Saved in checkpoints: every probe's next sample time (line probes: the next of their `at`
/// times) and its number of rows.
class MemoryProbes final : public Observer {
 public:
  explicit MemoryProbes(std::vector<Probe> probes) : probes_(std::move(probes)) {
    for (const Probe& p : probes_) {
      Table table;
      const std::string header = p.Header();
      std::size_t start = 0;
      while (start <= header.size()) {
        const std::size_t comma = std::min(header.find(',', start), header.size());
        table.columns.push_back(header.substr(start, comma - start));
        start = comma + 1;
      }
      table.values.resize(table.columns.size());
      tables_.push_back(std::move(table));
    }
  }

  void Observe(const Kernel& kernel, double t) override {
    const double tolerance = 1e-9 * kernel.macro_dt();
    for (std::size_t i = 0; i < probes_.size(); ++i) {
      const Probe& p = probes_[i];
      Table& table = tables_[i];
      if (p.is_line()) {
        const auto due = [&] {
          const auto k = static_cast<std::size_t>(table.next);
          return k < p.at.size() && t + tolerance >= p.at[k];
        };
        if (!due()) continue;
        Record(i, t);
        while (due()) table.next += 1;
        continue;
      }
      if (t + tolerance < table.next) continue;
      Record(i, t);
      if (p.every > 0) table.next = NextSampleTime(table.next, p.every, t + tolerance);
    }
  }
  void Finish(const Kernel& kernel) override {
    for (std::size_t i = 0; i < probes_.size(); ++i)
      if (probes_[i].is_line() && probes_[i].at.empty() && tables_[i].next == 0) {
        Record(i, kernel.time());  // once, at the end of the (first) run
        tables_[i].next = 1;
      }
  }
  void SaveState(StateWriter& out) override {
    out.BeginSection("PythonProbes", 2);
    out.WriteInt(static_cast<std::int64_t>(tables_.size()));
    for (const Table& table : tables_) {
      out.WriteDouble(table.next);
      out.WriteInt(table.rows);
    }
    out.EndSection();
  }
  void RestoreState(StateReader& in) override {
    in.BeginSection("PythonProbes", 2);
    const std::int64_t n = in.ReadInt();
    if (n != static_cast<std::int64_t>(tables_.size()))
      throw InputError(fmt::format("the checkpoint has {} probes recorded in memory, this scene {}",
                                   n, tables_.size()));
    pending_.clear();
    for (std::int64_t i = 0; i < n; ++i) {
      const double next = in.ReadDouble();
      pending_.emplace_back(next, in.ReadInt());
    }
    in.EndSection();
  }
  // Rows after the checkpoint's are dropped (a restore within this simulation goes back in
  // time); rows before it that a fresh simulation never recorded stay missing.
  void CommitRestore() override {
    for (std::size_t i = 0; i < tables_.size(); ++i) {
      Table& table = tables_[i];
      table.next = pending_[i].first;
      if (table.rows > pending_[i].second) {
        const std::size_t keep = static_cast<std::size_t>(pending_[i].second);
        const std::size_t per_row = probes_[i].is_line() ? probes_[i].line.cols() : 1;
        for (auto& column : table.values)
          if (column.size() > keep * per_row) column.resize(keep * per_row);
        if (table.times.size() > keep) table.times.resize(keep);
        table.rows = pending_[i].second;
      }
    }
  }

  /// Every probe's columns as NumPy arrays (copies), by probe name. Point and region probes:
  /// {"time": (rows,), column: (rows,)}. Line probes: {"time": (rows,), "distance", "x", "y",
  /// "z": (points,), column: (rows, points)}.
  [[nodiscard]] py::dict ToDict() const {
    py::dict result;
    for (std::size_t i = 0; i < probes_.size(); ++i) {
      const Table& table = tables_[i];
      py::dict columns;
      if (!probes_[i].is_line()) {
        for (std::size_t c = 0; c < table.columns.size(); ++c)
          columns[py::str(table.columns[c])] = Array(table.values[c]);
      } else {
        const Probe& p = probes_[i];
        const auto points = static_cast<py::ssize_t>(p.line.cols());
        columns["time"] = Array(table.times);
        columns["distance"] = Array(p.distance);
        for (int k = 0; k < 3; ++k) {
          std::vector<double> coordinate(static_cast<std::size_t>(points));
          for (py::ssize_t j = 0; j < points; ++j) coordinate[j] = p.line(k, j);
          columns[py::str(std::string(1, "xyz"[k]))] = Array(coordinate);
        }
        for (std::size_t c = 5; c < table.columns.size(); ++c)
          columns[py::str(table.columns[c])] = py::array_t<double>(
              {static_cast<py::ssize_t>(table.rows), points}, table.values[c].data());
      }
      result[py::str(probes_[i].name)] = columns;
    }
    return result;
  }

 private:
  struct Table {
    std::vector<std::string> columns;
    /// Point and region probes: one value per row and column (time first). Line probes: the
    /// field columns (after time, distance, x, y, z) row after row, one value per point.
    std::vector<std::vector<double>> values;
    std::vector<double> times;  // line probes: the sample times
    double next = 0;            // the next sample time (line probes: index into `at`)
    std::int64_t rows = 0;
  };
  static py::array_t<double> Array(const std::vector<double>& v) {
    return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
  }
  void Record(std::size_t i, double t) {
    const Probe& p = probes_[i];
    Table& table = tables_[i];
    p.Sample(row_);
    if (!p.is_line()) {
      table.values[0].push_back(t);
      for (std::size_t c = 0; c < row_.size() && c + 1 < table.values.size(); ++c)
        table.values[c + 1].push_back(row_[c]);
    } else {
      // Sample: per point, distance, x, y, z, then the field columns.
      const std::size_t width = table.columns.size() - 1, points = p.line.cols();
      table.times.push_back(t);
      for (std::size_t j = 0; j < points; ++j)
        for (std::size_t c = 5; c < table.columns.size(); ++c)
          table.values[c].push_back(row_[j * width + (c - 1)]);
    }
    ++table.rows;
  }

  std::vector<Probe> probes_;
  std::vector<Table> tables_;
  std::vector<double> row_;
  std::vector<std::pair<double, std::int64_t>> pending_;
};

}  // namespace gipsi::python
