#include "gipsi/viz/render/plot.h"

#include <plplot.h>
#include <sys/statvfs.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/file_io.h"
#include "gipsi/io/text_reader.h"

namespace gipsi::viz {
namespace {

bool HasDevice(const std::string& name) {
  // PLplot fills caller-owned arrays of at most `count` entries.
  std::vector<const char*> menu_storage(256), name_storage(256);
  const char** menus = menu_storage.data();
  const char** names = name_storage.data();
  int count = static_cast<int>(name_storage.size());
  plgDevs(&menus, &names, &count);
  bool found = false;
  for (int i = 0; i < count; ++i) found = found || name == names[i];
  return found;
}

/// [lo, hi] of the finite values, widened by 5 % (or by 1 around a constant).
std::pair<double, double> Range(const std::vector<PlotData::Series>& series, bool x) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& s : series)
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      const double v = x ? s.x[i] : s.y[i];
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  if (!(lo <= hi)) return {0, 0};
  const double pad =
      hi > lo ? 0.05 * (hi - lo) : std::max(1e-12, 0.1 * std::abs(lo)) + 1.0 * (lo == 0);
  return {lo - pad, hi + pad};
}

}  // namespace

void WritePlot(const PlotData& data, const std::filesystem::path& file) {
  const auto ext = file.extension();
  const std::string device = ext == ".png" ? "pngcairo" : ext == ".svg" ? "svgcairo" : "";
  if (device.empty())
    ThrowInputError(file.string(), "", "expected a plot file name ending in .png or .svg");
  const auto [x0, x1] = Range(data.series, true);
  const auto [y0, y1] = Range(data.series, false);
  if (!(x1 > x0) || !(y1 > y0))
    ThrowInputError(file.string(), "", "nothing to plot: the columns hold no finite points");
  // PLplot draws into a temporary file (it exits the program on a file it cannot open: find
  // out first) and does not report failed writes; the image is checked to be complete, then
  // written atomically to `file` with every write checked.
  std::filesystem::path tmp = file;
  tmp += ".plot.tmp";
  {
    std::ofstream probe(tmp);
    if (!probe)
      throw OutputError(
          fmt::format("{}: cannot create the file: {}", file.string(), std::strerror(errno)));
  }
  if (!HasDevice(device))
    throw std::runtime_error(fmt::format(
        "PLplot has no '{}' driver (install plplot-driver-cairo) for {}", device, file.string()));

  plsdev(device.c_str());
  plsfnam(tmp.c_str());
  plspage(0, 0, data.width, data.height, 0, 0);
  constexpr int kFirstSeries = 3;
  plscmap0n(kFirstSeries + static_cast<int>(std::size(kPlotColors)));
  plscol0(0, 255, 255, 255);  // background
  plscol0(1, 0, 0, 0);        // axes and text
  plscol0(2, 215, 215, 215);  // grid
  for (std::size_t i = 0; i < std::size(kPlotColors); ++i)
    plscol0(static_cast<int>(kFirstSeries + i), (kPlotColors[i] >> 16) & 0xff,
            (kPlotColors[i] >> 8) & 0xff, kPlotColors[i] & 0xff);
  plinit();
  // Several series: the legend goes right of the axes, outside the data, in a strip as wide as
  // its longest label (about 0.6 em per character at PLplot's default size, plus the sample
  // line), so it never covers a curve; it is centred on the axes' height.
  const bool legend = data.series.size() > 1;
  double legend_fraction = 0;
  if (legend) {
    std::size_t longest = 0;
    for (const auto& series : data.series) longest = std::max(longest, series.label.size());
    legend_fraction = std::min(0.45, (6.5 * double(longest) + 90.0) / data.width);
  }
  pladv(0);
  plvpor(0.1, 0.95 - legend_fraction, 0.12, 0.9);
  plwind(x0, x1, y0, y1);
  plcol0(2);
  plwidth(1.0);
  plbox("g", 0, 0, "g", 0, 0);
  plcol0(1);
  plbox("bcnst", 0, 0, "bcnstv", 0, 0);
  pllab(data.x_label.c_str(), data.y_label.c_str(), data.title.c_str());
  plwidth(2.0);
  std::vector<double> xs, ys;
  for (std::size_t s = 0; s < data.series.size(); ++s) {
    plcol0(static_cast<int>(kFirstSeries + s % std::size(kPlotColors)));
    const auto& series = data.series[s];
    auto flush = [&] {
      if (xs.size() >= 2) plline(static_cast<PLINT>(xs.size()), xs.data(), ys.data());
      xs.clear();
      ys.clear();
    };
    for (std::size_t i = 0; i < series.x.size(); ++i) {
      if (std::isfinite(series.x[i]) && std::isfinite(series.y[i])) {
        xs.push_back(series.x[i]);
        ys.push_back(series.y[i]);
      } else {
        flush();
      }
    }
    flush();
  }
  if (legend) {
    const std::size_t count = data.series.size();
    const auto n = static_cast<PLINT>(count);
    std::vector<PLINT> options(count, PL_LEGEND_LINE), colors(count), text_colors(count, 1),
        styles(count, 1);
    std::vector<PLFLT> widths(count, 2.0);
    std::vector<const char*> text(count);
    for (std::size_t i = 0; i < count; ++i) {
      colors[i] = static_cast<PLINT>(kFirstSeries + i % std::size(kPlotColors));
      text[i] = data.series[i].label.c_str();
    }
    PLFLT legend_width = 0, legend_height = 0;
    plwidth(1.0);
    pllegend(&legend_width, &legend_height, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
             PL_POSITION_RIGHT | PL_POSITION_OUTSIDE, 0.02, 0.0, 0.08, 0, 1, 1, 0, 0, n,
             options.data(), 1.0, 0.8, 2.0, 0.0, text_colors.data(), text.data(), nullptr, nullptr,
             nullptr, nullptr, colors.data(), styles.data(), widths.data(), nullptr, nullptr,
             nullptr, nullptr);
  }
  plend();
  std::string bytes;
  try {
    bytes = internal::ReadFileBytes(tmp);
  } catch (const InputError& e) {
    std::filesystem::remove(tmp);
    throw OutputError(e.what());
  }
  std::filesystem::remove(tmp);
  const bool complete = ext == ".png" ? bytes.ends_with(std::string_view("IEND\xae\x42\x60\x82", 8))
                                      : bytes.find("</svg>") != std::string::npos;
  if (!complete) {
    struct statvfs disk {};
    const bool full =
        ::statvfs(file.parent_path().empty() ? "." : file.parent_path().c_str(), &disk) == 0 &&
        disk.f_bavail == 0;
    throw OutputError(fmt::format(
        "{}: cannot write: {}", file.string(),
        full ? std::strerror(ENOSPC) : "the plotting library wrote an incomplete image"));
  }
  WriteFileAtomically(file, bytes);
}

std::vector<std::filesystem::path> WritePlots(const std::vector<PlotSpec>& specs,
                                              const std::filesystem::path& directory) {
  std::vector<std::filesystem::path> files;
  for (const PlotSpec& spec : specs) {
    const PlotData data = LoadPlotData(spec, directory / "probes");
    files.push_back(directory / spec.file);
    WritePlot(data, files.back());
  }
  return files;
}

}  // namespace gipsi::viz
