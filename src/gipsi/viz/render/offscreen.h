#pragma once
/// @file
/// Off-screen rendering without a window or display: an OSMesa (Mesa's software rasteriser,
/// Debian package libosmesa6-dev) OpenGL 3.3 core context, and `gipsi snapshot`'s pipeline:
/// run a scene to a time, fill its display buffers, draw them and write a PNG.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "gipsi/viz/camera.h"
#include "gipsi/viz/display_manager.h"
#include "gipsi/viz/render/gl_api.h"
#include "gipsi/viz/render/image.h"
#include "gipsi/viz/render/surface_renderer.h"

namespace gipsi {
struct Scene;
}

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

/// Options of `gipsi snapshot`. Plain struct.
struct SnapshotOptions {
  double time = 0;  ///< simulated time to render at [s] (0: the initial state)
  int width = 800, height = 600;
  int supersample = 2;  ///< anti-aliasing: render at this multiple of the size, then average
  Camera camera;        ///< target and (unless distance_given) distance are fitted
  RenderOptions render;
  bool labels = true;  ///< time, colour-bar values and field name (needs fonts-dejavu-core)
  std::vector<std::pair<std::string, ColorSpec>> colors;  ///< per object
  std::vector<std::string> show, hide;  ///< objects shown or hidden whatever the scene says
  std::vector<std::string> as;          ///< "OBJECT:lines" etc.: geometry whatever the scene says
};

/// What a snapshot did, for the command line's summary. Plain struct.
struct SnapshotResult {
  double time = 0;         ///< simulated time reached
  std::string gl;          ///< OffscreenContext::Description()
  FrameBuffers frame;      ///< what was drawn
  bool run_ok = true;      ///< false if the run diverged before `time`
  std::string diagnostic;  ///< why, when !run_ok
};

/// Draws the time at the bottom left and, when `frame` has a colour bar, its range and field
/// name beside it, into an image rendered at `supersample` times its size and downsampled.
/// Does nothing if the font is missing.
void DrawLabels(Image& image, const FrameBuffers& frame, const RenderOptions& render,
                int supersample);

/// Runs `scene` (without outputs) to `options.time`, draws every object as the scene's
/// "display" keys say (colours replaced by `options.colors`; hidden objects as
/// `options.render.hidden` says, else as the scene's "visible") off screen and returns the
/// image. Throws InputError for bad colour specs, std::runtime_error if rendering
/// is unavailable.
Image RenderSnapshot(Scene& scene, SnapshotOptions options, SnapshotResult* result = nullptr);

}  // namespace gipsi::viz
