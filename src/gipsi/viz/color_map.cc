#include "gipsi/viz/color_map.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi::viz {
namespace {

Rgb Hex(unsigned rgb) {
  return {static_cast<float>((rgb >> 16) & 0xff) / 255.0f,
          static_cast<float>((rgb >> 8) & 0xff) / 255.0f, static_cast<float>(rgb & 0xff) / 255.0f};
}

std::vector<Rgb> Anchors(std::string_view name) {
  if (name == "viridis")
    return {Hex(0x440154), Hex(0x482878), Hex(0x3e4989), Hex(0x31688e), Hex(0x26828e),
            Hex(0x1f9e89), Hex(0x35b779), Hex(0x6ece58), Hex(0xb5de2b), Hex(0xfde725)};
  if (name == "cool-warm")  // Moreland (2009): ends (59,76,192), (180,4,38); mid (221,221,221)
    return {Hex(0x3b4cc0), Hex(0xdddddd), Hex(0xb40426)};
  if (name == "grey") return {Hex(0x000000), Hex(0xffffff)};
  if (name == "rainbow")
    return {Hex(0x0000ff), Hex(0x00ffff), Hex(0x00ff00), Hex(0xffff00), Hex(0xff0000)};
  return {};
}

}  // namespace

std::vector<std::string> ColorMap::Names() { return ColorMapNames(); }

ColorMap ColorMap::Named(std::string_view name) {
  CheckColorMapName(name);
  std::vector<Rgb> anchors = Anchors(name);
  GIPSI_CHECK(!anchors.empty(), "colour map '{}' is named but has no colours", name);
  return ColorMap(std::string(name), std::move(anchors));
}

Rgb ColorMap::At(double s) const {
  if (std::isnan(s)) return kNanColor;
  s = std::clamp(s, 0.0, 1.0);
  const double x = s * static_cast<double>(anchors_.size() - 1);
  const std::size_t i = std::min(static_cast<std::size_t>(x), anchors_.size() - 2);
  const auto f = static_cast<float>(x - static_cast<double>(i));
  const Rgb& a = anchors_[i];
  const Rgb& b = anchors_[i + 1];
  return {a.r + f * (b.r - a.r), a.g + f * (b.g - a.g), a.b + f * (b.b - a.b)};
}

Rgb ColorMap::Map(double value, double lo, double hi) const {
  if (std::isnan(value)) return kNanColor;
  if (!(hi > lo)) return At(0.5);
  return At((value - lo) / (hi - lo));
}

}  // namespace gipsi::viz
