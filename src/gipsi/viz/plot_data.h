#pragma once
/// @file
/// The data of a scene's plots (io/plot_spec.h), read from the probes' CSV files and ready to
/// draw, and how the viewer's live plots label and scale a probe column.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/io/plot_spec.h"
#include "gipsi/io/probes.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// A plot's data, ready to draw. Plain struct.
struct PlotData {
  struct Series {
    std::string label;
    std::vector<double> x, y;  ///< same length; non-finite points break the line
  };
  std::string title, x_label, y_label;
  std::vector<Series> series;
  int width = 800, height = 500;
};

/// Reads the columns of `spec` from `<probe_dir>/<probe>.csv`; throws InputError naming the
/// file for a missing file or column.
PlotData LoadPlotData(const PlotSpec& spec, const std::filesystem::path& probe_dir);

/// Splits (x, y) into one series per run of equal `key` values (e.g. the rows of one sample
/// time of a line probe), labelled "`label` at t = VALUE s" (`key_name` "time") or "`label` at
/// KEY_NAME = VALUE" when there is more than one run, else `label`. Sizes must agree (checked).
std::vector<PlotData::Series> SplitSeries(const std::string& label, const std::vector<double>& x,
                                          const std::vector<double>& y,
                                          const std::vector<double>& key,
                                          const std::string& key_name = "time");

/// A probe column as plots label it: its last dotted part with spaces for underscores
/// ("blood.lv_pressure" → "lv pressure", "displacement_z" → "displacement z"), not the probe's
/// internal path.
std::string ReadableColumn(const std::string& column);

/// How a live plot shows one probe column (the viewer's traces). Plain struct.
struct ColumnDisplay {
  std::string label;  ///< readable: "lv pressure" for the column "blood.lv_pressure"
  std::string unit;   ///< the unit it is shown in ("" for none)
  double scale = 1;   ///< from the column's SI values to `unit`
  /// The field's no-data marker (FieldInfo::no_data) in SI, if it has one: shown as "not yet".
  std::optional<double> no_data;
};

/// How to show column `column` of `probe`: in the unit a plot of the scene (`plots`) draws it in
/// (e.g. mmHg for a pressure the scene plots in mmHg), else its field's SI unit; labelled by the
/// column's last dotted part with spaces for underscores.
ColumnDisplay DisplayOfColumn(const Probe& probe, const std::string& column,
                              const std::vector<PlotSpec>& plots);

}  // namespace gipsi::viz
GIPSI_EXPORT_END
