#pragma once
/// @file
/// `SurfaceRenderer`: draws published `FrameBuffers` with OpenGL 3.3 core — lit, two-sided
/// surfaces in their vertex colours, optional wire edges, unshaded line sets (GL_LINES) and
/// point sets (GL_POINTS), and a colour bar. It reads only the
/// frame it is given (never simulation state), so the same code serves the off-screen snapshot
/// and the interactive viewer.

#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/viz/camera.h"
#include "gipsi/viz/color_map.h"
#include "gipsi/viz/render/gl_api.h"
#include "gipsi/viz/render_buffers.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

/// What to draw besides the surfaces. Plain struct.
struct RenderOptions {
  Rgb background{1.0f, 1.0f, 1.0f};
  bool wireframe = false;    ///< dark triangle edges over the surfaces
  bool lighting = true;      ///< false: unshaded, every pixel shows its colour-map colour
  bool color_bar = true;     ///< a vertical colour bar at the right edge for the first surface
                             ///< coloured by a field
  std::vector<bool> hidden;  ///< surface i is not drawn if hidden[i] (shorter = visible)
  /// Per surface: draw its triangle edges (overrides SurfaceBuffers::wireframe; shorter = the
  /// surface's own choice). `wireframe` above draws them for all.
  std::vector<bool> edges;
  int viewport_x = 0;  ///< left edge of the drawing area in the framebuffer (pixels)
  /// Framebuffer pixels per image pixel (the snapshot's supersampling factor): line widths and
  /// point sizes are multiplied by it.
  float pixel_scale = 1;
};

/// The surface whose colours the colour bar explains: the first visible one coloured by a
/// field, or nullptr (then no bar is drawn and the scene uses the whole width).
const SurfaceBuffers* LegendSurface(const FrameBuffers& frame, const RenderOptions& options);

/// Where the colour bar goes in a `width` by `height` image, in pixels from the top-left: the
/// scene is drawn left of `strip_x0`; the bar spans [x0, x1) by [y0, y1) and its labels start
/// at `label_x`. Plain struct.
struct ColorBarLayout {
  int strip_x0, x0, x1, y0, y1, label_x;
};
ColorBarLayout LayoutColorBar(int width, int height);

/// Lighting: a headlight along the view direction, two-sided, colour · (kAmbient + (1 -
/// kAmbient) · |n · view|), so a face seen head-on shows its colour exactly.
inline constexpr float kAmbient = 0.3f;

/// Owns the GL program and buffers. Construct and destroy with the context current. Not
/// copyable or movable.
class SurfaceRenderer {
 public:
  /// Compiles the shaders; throws std::runtime_error with the GL log if that fails.
  explicit SurfaceRenderer(const GlApi& gl);
  ~SurfaceRenderer();
  SurfaceRenderer(const SurfaceRenderer&) = delete;
  SurfaceRenderer& operator=(const SurfaceRenderer&) = delete;

  /// Clears the bound framebuffer's `width` by `height` viewport and draws `frame` from
  /// `camera` (in the part left of the colour bar's strip when there is a bar).
  void Draw(const FrameBuffers& frame, const Camera& camera, int width, int height,
            const RenderOptions& options);

 private:
  struct GpuMesh {
    GLuint vao = 0, ebo = 0;
    GLuint vbo[3] = {0, 0, 0};  // positions, normals, colours
  };
  void Upload(GpuMesh& mesh, const float* positions, const float* normals, const float* colors,
              std::size_t num_vertices, const std::uint32_t* indices, std::size_t num_indices);
  void DrawColorBar(const SurfaceBuffers& surface, int width, int height);

  const GlApi& gl_;
  GLuint program_ = 0;
  GLint u_view_ = -1, u_projection_ = -1, u_override_ = -1, u_use_override_ = -1;
  GLint u_ambient_ = -1, u_point_size_ = -1;
  std::vector<GpuMesh> meshes_;
  GpuMesh bar_;
};

}  // namespace gipsi::viz
GIPSI_EXPORT_END
