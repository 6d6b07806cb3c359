#pragma once
/// @file
/// Colour maps: a scalar in [lo, hi] to an sRGB colour, for colouring display surfaces by a
/// field (transmembrane potential, stress, displacement magnitude) and for legends.

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/io/display_spec.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// A named colour map, piecewise linear in sRGB between evenly spaced anchor colours.
/// Copyable and movable.
class ColorMap {
 public:
  /// The map called `name`: "viridis" (perceptually uniform, matplotlib's default; anchors at
  /// its ten published 1/9 steps), "cool-warm" (Moreland's diverging blue–grey–red, through its
  /// published end and mid points), "grey" (black to white) or "rainbow" (blue–cyan–green–
  /// yellow–red). Throws InputError listing the names for any other name.
  static ColorMap Named(std::string_view name);
  /// The names Named accepts (ColorMapNames of io/display_spec.h).
  static std::vector<std::string> Names();

  [[nodiscard]] const std::string& name() const { return name_; }
  /// The colour of `value` on [lo, hi] (clamped; lo == hi gives the middle colour; NaN gives
  /// magenta so it stands out).
  [[nodiscard]] Rgb Map(double value, double lo, double hi) const;
  /// The colour at s in [0, 1] (clamped).
  [[nodiscard]] Rgb At(double s) const;

 private:
  ColorMap(std::string name, std::vector<Rgb> anchors)
      : name_(std::move(name)), anchors_(std::move(anchors)) {}
  std::string name_;
  std::vector<Rgb> anchors_;  // at s = i / (n - 1)
};

/// Colour used for NaN values.
inline constexpr Rgb kNanColor{1.0f, 0.0f, 1.0f};

}  // namespace gipsi::viz
GIPSI_EXPORT_END
