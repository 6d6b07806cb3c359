#include "gipsi/viz/plot_spec.h"

#include <algorithm>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gipsi/viz/csv_table.h"

namespace gipsi::viz {
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

PlotSpec ParsePlotSpec(const JsonNode& node, const std::vector<Probe>& probes) {
  node.CheckKeys({"file", "x", "y", "title", "size"});
  PlotSpec spec;
  const JsonNode file = node.At("file");
  spec.file = file.AsString();
  const auto ext = std::filesystem::path(spec.file).extension();
  if ((ext != ".png" && ext != ".svg") || spec.file.find("..") != std::string::npos)
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
  if (spec.x)
    for (std::size_t i = 0; i < spec.y.size(); ++i)
      if (spec.y[i].probe != spec.x->probe)
        (y.is_string() ? y : y.Item(i))
            .Fail(fmt::format("comes from probe '{}', but x comes from probe '{}': a plot "
                              "against a column other than time needs both from one probe",
                              spec.y[i].probe, spec.x->probe));
  if (auto size = node.Find("size")) {
    const auto v = size->AsInts();
    if (v.size() != 2 || v[0] < 100 || v[1] < 100 || v[0] > 8192 || v[1] > 8192)
      size->Expected("[width, height] in pixels, each in [100, 8192]");
    spec.width = static_cast<int>(v[0]);
    spec.height = static_cast<int>(v[1]);
  }
  return spec;
}

PlotData LoadPlotData(const PlotSpec& spec, const std::filesystem::path& probe_dir) {
  PlotData data;
  data.title = spec.title;
  data.width = spec.width;
  data.height = spec.height;
  auto label = [](const ColumnRef& c) { return c.probe + "." + c.column; };
  data.x_label = spec.x ? label(*spec.x) : "time [s]";
  std::map<std::string, CsvTable> tables;
  auto table = [&](const std::string& probe) -> const CsvTable& {
    auto it = tables.find(probe);
    if (it == tables.end()) it = tables.emplace(probe, ReadCsv(probe_dir / (probe + ".csv"))).first;
    return it->second;
  };
  for (const ColumnRef& y : spec.y) {
    const CsvTable& t = table(y.probe);
    data.series.push_back(
        {label(y), spec.x ? t.Column(spec.x->column) : t.Column("time"), t.Column(y.column)});
  }
  data.y_label = spec.y.size() == 1 ? label(spec.y[0]) : "";
  return data;
}

}  // namespace gipsi::viz
