#include "gipsi/io/plot_spec.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/base/error.h"
#include "gipsi/base/units.h"

namespace gipsi {
namespace {

ColumnRef ParseColumn(const JsonNode& node, const std::vector<Probe>& probes) {
  const std::string text = node.AsString();
  const std::size_t dot = text.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == text.size())
    node.Expected("PROBE.COLUMN, e.g. \"tip.displacement_z\"");
  ColumnRef ref{text.substr(0, dot), text.substr(dot + 1)};
  std::vector<std::string> names;
  for (const Probe& probe : probes) {
    if (probe.name != ref.probe) {
      names.push_back(probe.name);
      continue;
    }
    const auto columns = ProbeColumns(probe);
    if (std::find(columns.begin(), columns.end(), ref.column) == columns.end())
      node.Fail(fmt::format("probe '{}' has no column '{}'{}; its columns are: {}", ref.probe,
                            ref.column, SuggestClosest(ref.column, columns),
                            fmt::join(columns, ", ")));
    return ref;
  }
  node.Fail(fmt::format("no probe named '{}'{} in 'probes'", ref.probe,
                        SuggestClosest(ref.probe, names)));
}

}  // namespace

std::vector<std::string> ProbeColumns(const Probe& probe) {
  std::vector<std::string> columns;
  const std::string header = probe.Header();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = header.find(',', start);
    columns.push_back(header.substr(start, comma - start));
    if (comma == std::string::npos) return columns;
    start = comma + 1;
  }
}

std::string ProbeColumnUnits(const Probe& probe, const std::string& column) {
  if (column == "time") return "s";
  if (probe.is_line() && (column == "distance" || column == "x" || column == "y" || column == "z"))
    return "m";
  for (FieldId id : probe.fields) {
    const FieldInfo& info = probe.object->field_info(id);
    if (column == info.name ||
        (column.size() > info.name.size() + 1 &&
         column.compare(0, info.name.size(), info.name) == 0 && column[info.name.size()] == '_'))
      return info.units == "1" ? "" : info.units;
  }
  return "";
}

namespace {

/// The unit an axis is drawn in and the factor from the columns' SI unit `si` to it: the
/// node's unit if given (it must convert from `si`), else `si` itself.
void AxisUnit(const JsonNode* node, const std::string& si, std::string& unit, double& scale) {
  unit = si;
  scale = 1;
  if (node == nullptr) return;
  const std::string wanted = node->AsString();
  try {
    scale = 1 / UnitFactor(wanted, si.empty() ? "1" : si);
  } catch (const std::invalid_argument&) {
    node->Expected(fmt::format("a unit that converts from the column's unit '{}'",
                               si.empty() ? "1 (dimensionless)" : si));
  }
  if (!std::isfinite(scale) || scale == 0)
    node->Expected(fmt::format("a unit that converts from '{}'", si));
  unit = wanted;
}

}  // namespace

PlotSpec ParsePlotSpec(const JsonNode& node, const std::vector<Probe>& probes) {
  node.CheckKeys({"file", "x", "y", "title", "size", "x_unit", "y_unit"});
  PlotSpec spec;
  const JsonNode file = node.At("file");
  spec.file = file.AsString();
  const auto ext = std::filesystem::path(spec.file).extension();
  if ((ext != ".png" && ext != ".svg") || spec.file.find("..") != std::string::npos ||
      std::filesystem::path(spec.file).has_root_path())
    file.Expected("a file name ending in .png or .svg (inside the output directory)");
  spec.title = node.String("title", "");
  if (auto x = node.Find("x"); x && x->AsString() != "time") spec.x = ParseColumn(*x, probes);
  const JsonNode y = node.At("y");
  if (y.is_string()) {
    spec.y.push_back(ParseColumn(y, probes));
  } else {
    const auto items = y.Items();
    if (items.empty()) y.Expected("a column or a non-empty array of columns");
    for (const auto& item : items) spec.y.push_back(ParseColumn(item, probes));
  }
  const auto line_probe = [&](const std::string& name) {
    return std::any_of(probes.begin(), probes.end(),
                       [&](const Probe& p) { return p.name == name && p.is_line(); });
  };
  if (line_probe(spec.y[0].probe)) {
    spec.profile = true;
    if (auto x = node.Find("x"); x && x->AsString() == "time")
      x->Fail(
          fmt::format("probe '{}' samples along a line: plot against its 'distance' (the "
                      "default) or a coordinate, e.g. \"{}.x\"",
                      spec.y[0].probe, spec.y[0].probe));
    if (!spec.x) spec.x = ColumnRef{spec.y[0].probe, "distance"};
  } else if (!spec.x) {
    for (std::size_t i = 0; i < spec.y.size(); ++i)
      if (line_probe(spec.y[i].probe))
        (y.is_string() ? y : y.Item(i))
            .Fail(fmt::format("comes from line probe '{}', but the first column does not: plot "
                              "a line probe's columns on their own",
                              spec.y[i].probe));
  }
  if (spec.x)
    for (std::size_t i = 0; i < spec.y.size(); ++i)
      if (spec.y[i].probe != spec.x->probe)
        (y.is_string() ? y : y.Item(i))
            .Fail(fmt::format("comes from probe '{}', but x comes from probe '{}': a plot "
                              "against a column other than time needs both from one probe",
                              spec.y[i].probe, spec.x->probe));
  // Units: the columns' SI units, or the plot's; all y columns share one axis, so one unit.
  auto probe_of = [&](const ColumnRef& c) -> const Probe& {
    return *std::find_if(probes.begin(), probes.end(),
                         [&](const Probe& p) { return p.name == c.probe; });
  };
  const std::string x_si = spec.x ? ProbeColumnUnits(probe_of(*spec.x), spec.x->column) : "s";
  const std::string y_si = ProbeColumnUnits(probe_of(spec.y[0]), spec.y[0].column);
  const auto y_unit = node.Find("y_unit");
  for (std::size_t i = 1; i < spec.y.size(); ++i) {
    const std::string other = ProbeColumnUnits(probe_of(spec.y[i]), spec.y[i].column);
    if (y_unit && other != y_si)
      y_unit->Fail(
          fmt::format("the y columns have different units ('{}' and '{}'): one y_unit "
                      "cannot convert both",
                      y_si, other));
  }
  const auto x_unit = node.Find("x_unit");
  AxisUnit(x_unit ? &*x_unit : nullptr, x_si, spec.x_unit, spec.x_scale);
  AxisUnit(y_unit ? &*y_unit : nullptr, y_si, spec.y_unit, spec.y_scale);
  if (auto size = node.Find("size")) {
    const auto v = size->AsInts();
    if (v.size() != 2 || v[0] < 100 || v[1] < 100 || v[0] > 8192 || v[1] > 8192)
      size->Expected("[width, height] in pixels, each in [100, 8192]");
    spec.width = static_cast<int>(v[0]);
    spec.height = static_cast<int>(v[1]);
  }
  return spec;
}

}  // namespace gipsi
