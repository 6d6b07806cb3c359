#pragma once
/// @file
/// Plots a scene asks for at the end of a run (`"outputs": {"plots": [...]}`), e.g. a trace over
/// time or a pressure-volume loop, from the probes' CSV columns:
///
///   "plots": [
///     {"file": "tip.png", "y": ["tip.displacement_z"]},
///     {"file": "pv.svg", "x": "lv.volume", "y": "lv.pressure", "title": "PV loop"}
///   ]
/// A column is named `PROBE.COLUMN` with the probe's CSV column (`time`, `displacement_x`, ...);
/// `x` defaults to `time` (each trace against its own probe's time); any other `x` must come
/// from the same probe as every `y`. For a line probe (a profile along a line) `x` defaults to
/// its `distance`, and each sample time becomes its own curve:
///
///     {"file": "activation.png", "y": "diagonal.activation_time"}
///
/// `x_unit` and `y_unit` draw the axes in other units than the fields' SI units (converted by
/// UDUNITS-2, e.g. a pressure-volume loop in mL and mmHg):
///
///     {"file": "pv.png", "x": "pv.lv_volume", "y": "pv.lv_pressure",
///      "x_unit": "mL", "y_unit": "mmHg"}
///
/// These are plain specifications, checked against the scene's probes when it loads; the viz
/// layer reads the CSVs and draws them (viz/plot_data.h).

#include <optional>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/io/probes.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// One probe column. Plain struct.
struct ColumnRef {
  std::string probe;   ///< probe name
  std::string column;  ///< CSV column, e.g. "displacement_z"
};

/// One plot. Plain struct.
struct PlotSpec {
  std::string file;  ///< output file, .png or .svg, relative to the run's output directory
  std::string title;
  std::optional<ColumnRef> x;  ///< absent: time
  std::vector<ColumnRef> y;    ///< at least one
  /// The columns come from a line probe: one curve per sample time (the rows of one time).
  bool profile = false;
  /// Axis units as shown in the labels (the columns' SI units unless the plot names others),
  /// and the factors that convert the CSV values (SI) to them; "" for a dimensionless axis.
  std::string x_unit, y_unit;
  double x_scale = 1, y_scale = 1;
  int width = 800, height = 500;
};

/// Parses and checks one plot against the scene's probes (their names and CSV columns); throws
/// InputError naming the JSON path for an unknown probe or column, a bad file extension, an
/// `x` from another probe than a `y`, or a unit that does not parse or does not convert from
/// the column's SI unit.
PlotSpec ParsePlotSpec(const JsonNode& node, const std::vector<Probe>& probes);

/// The CSV columns a probe writes (its header split at commas).
std::vector<std::string> ProbeColumns(const Probe& probe);

/// The SI unit of one of a probe's CSV columns ("s" for time, "m" for a line probe's distance
/// and coordinates, else its field's unit); empty if the probe has no such column.
std::string ProbeColumnUnits(const Probe& probe, const std::string& column);

}  // namespace gipsi
GIPSI_EXPORT_END
