#include "gipsi/viz/render/text.h"

#include <stb_truetype.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>

namespace gipsi::viz {

struct TextPainter::Font {
  std::vector<unsigned char> data;
  stbtt_fontinfo info{};
};

TextPainter::TextPainter(std::unique_ptr<Font> font) : font_(std::move(font)) {}
TextPainter::~TextPainter() = default;
TextPainter::TextPainter(TextPainter&&) noexcept = default;
TextPainter& TextPainter::operator=(TextPainter&&) noexcept = default;

std::optional<TextPainter> TextPainter::Load() {
  std::ifstream in(kFontFile, std::ios::binary);
  if (!in) return std::nullopt;
  auto font = std::make_unique<Font>();
  font->data.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (font->data.empty() || !stbtt_InitFont(&font->info, font->data.data(),
                                            stbtt_GetFontOffsetForIndex(font->data.data(), 0)))
    return std::nullopt;
  return TextPainter(std::move(font));
}

int TextPainter::Width(std::string_view text, float size) const {
  const float scale = stbtt_ScaleForPixelHeight(&font_->info, size);
  float x = 0;
  for (char c : text) {
    if (static_cast<unsigned char>(c) >= 128) continue;
    int advance = 0, bearing = 0;
    stbtt_GetCodepointHMetrics(&font_->info, c, &advance, &bearing);
    x += float(advance) * scale;
  }
  return static_cast<int>(std::ceil(x));
}

void TextPainter::Draw(Image& image, int x, int y, std::string_view text, float size,
                       Rgb color) const {
  const float scale = stbtt_ScaleForPixelHeight(&font_->info, size);
  int ascent = 0, descent = 0, gap = 0;
  stbtt_GetFontVMetrics(&font_->info, &ascent, &descent, &gap);
  const int baseline = y + static_cast<int>(std::lround(float(ascent) * scale));
  float pen = float(x);
  std::vector<unsigned char> glyph;
  for (char c : text) {
    if (static_cast<unsigned char>(c) >= 128) continue;
    int advance = 0, bearing = 0;
    stbtt_GetCodepointHMetrics(&font_->info, c, &advance, &bearing);
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    stbtt_GetCodepointBitmapBox(&font_->info, c, scale, scale, &x0, &y0, &x1, &y1);
    const int w = x1 - x0, h = y1 - y0;
    if (w > 0 && h > 0) {
      glyph.assign(std::size_t(w) * std::size_t(h), 0);
      stbtt_MakeCodepointBitmap(&font_->info, glyph.data(), w, h, w, scale, scale, c);
      const int gx = static_cast<int>(std::lround(pen)) + x0, gy = baseline + y0;
      for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
          const int px = gx + i, py = gy + j;
          if (px < 0 || py < 0 || px >= image.width || py >= image.height) continue;
          const float a = glyph[std::size_t(j) * std::size_t(w) + std::size_t(i)] / 255.0f;
          std::uint8_t* p =
              &image.rgb[3 * (std::size_t(py) * std::size_t(image.width) + std::size_t(px))];
          const float target[3] = {color.r, color.g, color.b};
          for (int k = 0; k < 3; ++k)
            p[k] = static_cast<std::uint8_t>(
                std::lround((1 - a) * float(p[k]) + a * 255.0f * target[k]));
        }
    }
    pen += float(advance) * scale;
  }
}

}  // namespace gipsi::viz
