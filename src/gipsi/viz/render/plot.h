#pragma once
/// @file
/// Plots as PNG or SVG files through PLplot (Debian libplplot-dev with its cairo driver,
/// plplot-driver-cairo): traces over time, x-y loops (pressure-volume), from `PlotData`.

#include <filesystem>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/viz/plot_data.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// Line colours of the series, in order (then repeated), as 0xRRGGBB.
inline constexpr unsigned kPlotColors[] = {0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728,
                                           0x9467bd, 0x8c564b, 0xe377c2, 0x7f7f7f};

/// Draws `data` into `file`: PNG for ".png", SVG for ".svg" (cairo). Axes span the finite data
/// with 5 % margins; a legend names the series when there are several. PLplot keeps global
/// state: call from one thread at a time. Throws InputError for another extension or a plot
/// without finite points, std::runtime_error if the file cannot be written or the cairo
/// driver is missing.
void WritePlot(const PlotData& data, const std::filesystem::path& file);

/// Writes every plot of `specs` into `directory`, reading probe CSVs from `directory/probes`.
/// Returns the files written. Throws like LoadPlotData and WritePlot.
std::vector<std::filesystem::path> WritePlots(const std::vector<PlotSpec>& specs,
                                              const std::filesystem::path& directory);

}  // namespace gipsi::viz
GIPSI_EXPORT_END
