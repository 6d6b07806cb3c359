#include "gipsi/viz/plot_data.h"

#include <algorithm>
#include <map>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/viz/csv_table.h"

namespace gipsi::viz {

std::vector<PlotData::Series> SplitSeries(const std::string& label, const std::vector<double>& x,
                                          const std::vector<double>& y,
                                          const std::vector<double>& key,
                                          const std::string& key_name) {
  GIPSI_CHECK(x.size() == y.size() && y.size() == key.size());
  std::vector<PlotData::Series> out;
  for (std::size_t start = 0; start < key.size();) {
    std::size_t end = start + 1;
    while (end < key.size() && key[end] == key[start]) ++end;
    PlotData::Series series;
    series.label = key_name == "time"
                       ? fmt::format("{} at t = {:.4g} s", label, key[start])
                       : fmt::format("{} at {} = {:.4g}", label, key_name, key[start]);
    series.x.assign(x.begin() + std::ptrdiff_t(start), x.begin() + std::ptrdiff_t(end));
    series.y.assign(y.begin() + std::ptrdiff_t(start), y.begin() + std::ptrdiff_t(end));
    out.push_back(std::move(series));
    start = end;
  }
  if (out.size() == 1) out[0].label = label;
  return out;
}

std::string ReadableColumn(const std::string& column) {
  std::string label = column.substr(column.rfind('.') + 1);
  std::replace(label.begin(), label.end(), '_', ' ');
  return label;
}

PlotData LoadPlotData(const PlotSpec& spec, const std::filesystem::path& probe_dir) {
  PlotData data;
  data.title = spec.title;
  data.width = spec.width;
  data.height = spec.height;
  auto label = [](const ColumnRef& c) { return ReadableColumn(c.column); };
  auto with_unit = [](std::string text, const std::string& unit) {
    return unit.empty() ? text : text + " [" + unit + "]";
  };
  data.x_label = with_unit(spec.x ? label(*spec.x) : "time", spec.x_unit);
  auto scaled = [](std::vector<double> v, double factor) {
    if (factor != 1)
      for (double& value : v) value *= factor;
    return v;
  };
  std::map<std::string, CsvTable> tables;
  auto table = [&](const std::string& probe) -> const CsvTable& {
    auto it = tables.find(probe);
    if (it == tables.end()) it = tables.emplace(probe, ReadCsv(probe_dir / (probe + ".csv"))).first;
    return it->second;
  };
  for (const ColumnRef& y : spec.y) {
    const CsvTable& t = table(y.probe);
    const std::vector<double> x =
        scaled(spec.x ? t.Column(spec.x->column) : t.Column("time"), spec.x_scale);
    const std::vector<double> values = scaled(t.Column(y.column), spec.y_scale);
    if (spec.profile) {
      for (auto& series : SplitSeries(label(y), x, values, t.Column("time")))
        data.series.push_back(std::move(series));
    } else {
      data.series.push_back({label(y), x, values});
    }
  }
  data.y_label = spec.y.size() == 1 ? with_unit(label(spec.y[0]), spec.y_unit)
                                    : (spec.y_unit.empty() ? "" : "[" + spec.y_unit + "]");
  return data;
}

ColumnDisplay DisplayOfColumn(const Probe& probe, const std::string& column,
                              const std::vector<PlotSpec>& plots) {
  ColumnDisplay out;
  out.label = ReadableColumn(column);
  out.unit = ProbeColumnUnits(probe, column);
  for (const PlotSpec& plot : plots) {
    const auto same = [&](const ColumnRef& ref) {
      return ref.probe == probe.name && ref.column == column;
    };
    if (plot.x && same(*plot.x)) {
      out.unit = plot.x_unit;
      out.scale = plot.x_scale;
      break;
    }
    if (std::any_of(plot.y.begin(), plot.y.end(), same)) {
      out.unit = plot.y_unit;
      out.scale = plot.y_scale;
      break;
    }
  }
  for (FieldId id : probe.fields) {
    const FieldInfo& info = probe.object->field_info(id);
    if (info.components == 1 && column == info.name) out.no_data = info.no_data;
  }
  return out;
}

}  // namespace gipsi::viz
