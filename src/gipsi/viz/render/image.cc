#include "gipsi/viz/render/image.h"

#include <stb_image.h>
#include <stb_image_write.h>

#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/file_io.h"

namespace gipsi::viz {

void WritePng(const Image& image, const std::filesystem::path& file) {
  GIPSI_CHECK(image.rgb.size() == 3 * std::size_t(image.width) * std::size_t(image.height));
  // Encoded in memory, then written atomically with every write checked: stb's own file writer
  // ignores a failing fwrite/fclose and left 0-byte images on a full disk.
  std::string png;
  auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data),
                                               static_cast<std::size_t>(size));
  };
  if (!stbi_write_png_to_func(append, &png, image.width, image.height, 3, image.rgb.data(),
                              3 * image.width))
    throw OutputError(fmt::format("{}: cannot encode the PNG image", file.string()));
  WriteFileAtomically(file, png);
}

Image ReadPng(const std::filesystem::path& file) {
  int w = 0, h = 0, channels = 0;
  stbi_uc* data = stbi_load(file.c_str(), &w, &h, &channels, 3);
  if (!data)
    throw std::runtime_error(
        fmt::format("cannot read the image {}: {}", file.string(), stbi_failure_reason()));
  Image image{w, h, std::vector<std::uint8_t>(data, data + 3 * std::size_t(w) * std::size_t(h))};
  stbi_image_free(data);
  return image;
}

Image Downsample(const Image& image, int factor) {
  GIPSI_CHECK(factor >= 1 && image.width % factor == 0 && image.height % factor == 0);
  Image out{image.width / factor, image.height / factor, {}};
  out.rgb.resize(3 * std::size_t(out.width) * std::size_t(out.height));
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 3; ++c) {
        int sum = 0;
        for (int dy = 0; dy < factor; ++dy)
          for (int dx = 0; dx < factor; ++dx)
            sum += image.rgb[3 * (std::size_t(y * factor + dy) * std::size_t(image.width) +
                                  std::size_t(x * factor + dx)) +
                             std::size_t(c)];
        const int n = factor * factor;
        out.rgb[3 * (std::size_t(y) * std::size_t(out.width) + std::size_t(x)) + std::size_t(c)] =
            static_cast<std::uint8_t>((sum + n / 2) / n);
      }
  return out;
}

}  // namespace gipsi::viz
