#pragma once
/// @file
/// `Image`: 8-bit RGB pixels, top row first, and PNG files (through stb_image_write and
/// stb_image, Debian package libstb-dev).

#include <cstdint>
#include <filesystem>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/viz/color_map.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// Width by height RGB pixels, rows top to bottom. Copyable and movable.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< 3 * width * height bytes

  /// The colour of pixel (x, y), x to the right and y down from the top-left corner.
  [[nodiscard]] Rgb At(int x, int y) const {
    const std::size_t i = 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
    return {rgb[i] / 255.0f, rgb[i + 1] / 255.0f, rgb[i + 2] / 255.0f};
  }
};

/// Writes `image` as a PNG, atomically; throws OutputError naming the file and the reason.
void WritePng(const Image& image, const std::filesystem::path& file);
/// Reads a PNG (any channel count; converted to RGB); throws std::runtime_error naming the file.
Image ReadPng(const std::filesystem::path& file);

/// Averages each `factor` by `factor` block of pixels (anti-aliasing by supersampling).
/// Preconditions (checked): the size is a multiple of `factor`.
Image Downsample(const Image& image, int factor);

}  // namespace gipsi::viz
GIPSI_EXPORT_END
