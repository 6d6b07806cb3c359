#pragma once
/// @file
/// `TextPainter`: draws short labels (colour-bar values, field names, time) into an `Image`
/// with a TrueType font (DejaVu Sans from Debian's fonts-dejavu-core, rasterised by
/// stb_truetype).

#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/viz/render/image.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// Not copyable; movable.
class TextPainter {
 public:
  /// Loads the font; std::nullopt if the font file is missing (labels are then left out).
  static std::optional<TextPainter> Load();
  ~TextPainter();
  TextPainter(TextPainter&&) noexcept;
  TextPainter& operator=(TextPainter&&) noexcept;

  /// Width in pixels of `text` (ASCII; other bytes are skipped) at `size` pixels.
  [[nodiscard]] int Width(std::string_view text, float size) const;
  /// Draws `text` with its top-left corner at (x, y) (pixels from the image's top left),
  /// blending `color` over the image by glyph coverage; clipped to the image.
  void Draw(Image& image, int x, int y, std::string_view text, float size, Rgb color) const;

 private:
  struct Font;
  explicit TextPainter(std::unique_ptr<Font> font);
  std::unique_ptr<Font> font_;
};

/// Where the font is looked for.
inline constexpr const char* kFontFile = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

}  // namespace gipsi::viz
GIPSI_EXPORT_END
