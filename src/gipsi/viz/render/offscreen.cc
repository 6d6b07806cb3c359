#include "gipsi/viz/render/offscreen.h"

#include <GL/osmesa.h>

#include <stdexcept>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/viz/render/text.h"

namespace gipsi::viz {

struct OffscreenContext::Impl {
  OSMesaContext context = nullptr;
  std::vector<std::uint8_t> pixels;  // RGBA, bottom row first
};

OffscreenContext::OffscreenContext(int width, int height)
    : impl_(std::make_unique<Impl>()), width_(width), height_(height) {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw std::runtime_error(
        fmt::format("off-screen image size {} x {} is not in [1, 16384]", width, height));
  const int attributes[] = {OSMESA_FORMAT,
                            OSMESA_RGBA,
                            OSMESA_DEPTH_BITS,
                            24,
                            OSMESA_PROFILE,
                            OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION,
                            3,
                            OSMESA_CONTEXT_MINOR_VERSION,
                            3,
                            0};
  impl_->context = OSMesaCreateContextAttribs(attributes, nullptr);
  if (!impl_->context) throw std::runtime_error("OSMesa cannot create an OpenGL 3.3 core context");
  impl_->pixels.resize(4 * std::size_t(width) * std::size_t(height));
  if (!OSMesaMakeCurrent(impl_->context, impl_->pixels.data(), GL_UNSIGNED_BYTE, width, height)) {
    OSMesaDestroyContext(impl_->context);
    throw std::runtime_error("OSMesa cannot make its context current");
  }
  const std::string missing = gl_.Load(
      [](const char* name) { return reinterpret_cast<void*>(OSMesaGetProcAddress(name)); });
  if (!missing.empty()) {
    OSMesaDestroyContext(impl_->context);
    throw std::runtime_error(fmt::format("OSMesa lacks the OpenGL function {}", missing));
  }
}

OffscreenContext::~OffscreenContext() { OSMesaDestroyContext(impl_->context); }

std::string OffscreenContext::Description() const {
  auto text = [&](GLenum name) {
    const auto* s = reinterpret_cast<const char*>(gl_.GetString(name));
    return std::string(s ? s : "?");
  };
  return fmt::format("OpenGL {}, {}", text(GL_VERSION), text(GL_RENDERER));
}

Image OffscreenContext::ReadImage() const {
  gl_.Finish();
  Image image{width_, height_, {}};
  image.rgb.resize(3 * std::size_t(width_) * std::size_t(height_));
  for (int y = 0; y < height_; ++y) {
    const std::uint8_t* row = impl_->pixels.data() + 4 * std::size_t(height_ - 1 - y) * width_;
    std::uint8_t* out = image.rgb.data() + 3 * std::size_t(y) * width_;
    for (int x = 0; x < width_; ++x)
      for (int c = 0; c < 3; ++c) out[3 * x + c] = row[4 * x + c];
  }
  return image;
}

Image RenderFrame(const FrameBuffers& frame, FrameImageOptions options, std::string* gl) {
  GIPSI_CHECK(options.supersample >= 1 && options.supersample <= 4);
  const int k = options.supersample;
  options.render.pixel_scale = float(k);
  const int scene_width = LegendSurface(frame, options.render)
                              ? LayoutColorBar(options.width * k, options.height * k).strip_x0
                              : options.width * k;
  options.camera.FitTo(frame, double(scene_width) / (options.height * k));
  OffscreenContext context(options.width * k, options.height * k);
  if (gl) *gl = context.Description();
  {
    SurfaceRenderer renderer(context.gl());
    renderer.Draw(frame, options.camera, context.width(), context.height(), options.render);
  }
  Image image = Downsample(context.ReadImage(), k);
  if (options.labels) DrawLabels(image, frame, options.render, k);
  return image;
}

void DrawLabels(Image& image, const FrameBuffers& frame, const RenderOptions& render,
                int supersample) {
  const std::optional<TextPainter> painter = TextPainter::Load();
  if (!painter) return;
  const Rgb ink{0.1f, 0.1f, 0.1f};
  const float size = std::max(11.0f, float(image.height) / 32.0f);
  const int pad = static_cast<int>(size / 2);
  painter->Draw(image, pad, image.height - pad - static_cast<int>(size * 1.2f),
                fmt::format("t = {:.4g} s", frame.time), size, ink);
  const SurfaceBuffers* legend = LegendSurface(frame, render);
  if (!legend) return;
  ColorBarLayout bar = LayoutColorBar(image.width * supersample, image.height * supersample);
  for (int* v : {&bar.strip_x0, &bar.x0, &bar.x1, &bar.y0, &bar.y1, &bar.label_x})
    *v /= supersample;
  const int half = static_cast<int>(size * 0.6f);
  painter->Draw(image, bar.label_x, bar.y0 - half, fmt::format("{:.3g}", legend->range_hi), size,
                ink);
  painter->Draw(image, bar.label_x, bar.y1 - half, fmt::format("{:.3g}", legend->range_lo), size,
                ink);
  const std::string title = legend->units.empty() || legend->units == "1"
                                ? legend->field
                                : fmt::format("{} [{}]", legend->field, legend->units);
  const int title_x = std::min(bar.x0, image.width - pad - painter->Width(title, size));
  painter->Draw(image, std::max(0, title_x), bar.y0 - static_cast<int>(2.6f * size), title, size,
                ink);
}

}  // namespace gipsi::viz
