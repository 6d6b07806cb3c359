#pragma once
/// @file
/// Off-screen rendering without a window or display: an OSMesa (Mesa's software rasteriser,
/// Debian package libosmesa6-dev) OpenGL 3.3 core context, and drawing one frame of display
/// buffers into an image (`gipsi snapshot`, after it has run the scene and filled them).

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/viz/camera.h"
#include "gipsi/viz/render/gl_api.h"
#include "gipsi/viz/render/image.h"
#include "gipsi/viz/render/surface_renderer.h"
#include "gipsi/viz/render_buffers.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// A software OpenGL 3.3 core context drawing into memory. Makes itself current on the
/// constructing thread. Not copyable or movable.
class OffscreenContext {
 public:
  /// Throws std::runtime_error if OSMesa cannot create a 3.3 core context of that size.
  OffscreenContext(int width, int height);
  ~OffscreenContext();
  OffscreenContext(const OffscreenContext&) = delete;
  OffscreenContext& operator=(const OffscreenContext&) = delete;

  [[nodiscard]] const GlApi& gl() const { return gl_; }
  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }
  /// "OpenGL 3.3 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)".
  [[nodiscard]] std::string Description() const;
  /// The pixels drawn so far (GL's bottom-up rows flipped to top-down).
  [[nodiscard]] Image ReadImage() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  GlApi gl_;
  int width_, height_;
};

/// How one frame becomes an image. Plain struct.
struct FrameImageOptions {
  int width = 800, height = 600;
  int supersample = 2;  ///< anti-aliasing: render at this multiple of the size, then average
  Camera camera;        ///< target and (unless distance_given) distance are fitted to the frame
  RenderOptions render;
  bool labels = true;  ///< time, colour-bar values and field name (needs fonts-dejavu-core)
};

/// Draws the time at the bottom left and, when `frame` has a colour bar, its range and field
/// name beside it, into an image rendered at `supersample` times its size and downsampled.
/// Does nothing if the font is missing.
void DrawLabels(Image& image, const FrameBuffers& frame, const RenderOptions& render,
                int supersample);

/// Draws `frame` (filled by display managers, e.g. SceneDisplay::Fill) off screen with the
/// camera fitted to it, and returns the image; `gl`, if given, receives the context's
/// description (OffscreenContext::Description). Runs nothing: the caller brings the simulation
/// to the time it wants drawn. Throws std::runtime_error if rendering is unavailable.
Image RenderFrame(const FrameBuffers& frame, FrameImageOptions options, std::string* gl = nullptr);

}  // namespace gipsi::viz
GIPSI_EXPORT_END
