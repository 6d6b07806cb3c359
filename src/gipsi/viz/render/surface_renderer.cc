#include "gipsi/viz/render/surface_renderer.h"

#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace gipsi::viz {
namespace {

constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 color;
uniform mat4 view;
uniform mat4 projection;
uniform float point_size;
out vec3 v_normal;
out vec3 v_color;
void main() {
  v_normal = mat3(view) * normal;
  v_color = color;
  gl_Position = projection * view * vec4(position, 1.0);
  gl_PointSize = point_size;
}
)";

constexpr const char* kFragmentShader = R"(#version 330 core
in vec3 v_normal;
in vec3 v_color;
uniform vec3 override_color;
uniform int use_override;
uniform float ambient;
out vec4 frag_color;
void main() {
  float len = length(v_normal);
  float facing = len > 0.0 ? abs(v_normal.z) / len : 1.0;
  vec3 c = use_override != 0 ? override_color : v_color;
  frag_color = vec4(c * (ambient + (1.0 - ambient) * facing), 1.0);
}
)";

GLuint Compile(const GlApi& gl, GLenum type, const char* source) {
  GLuint shader = gl.CreateShader(type);
  gl.ShaderSource(shader, 1, &source, nullptr);
  gl.CompileShader(shader);
  GLint ok = 0;
  gl.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    gl.GetShaderInfoLog(shader, sizeof log, nullptr, log);
    gl.DeleteShader(shader);
    throw std::runtime_error(fmt::format("OpenGL shader does not compile: {}", log));
  }
  return shader;
}

}  // namespace

const SurfaceBuffers* LegendSurface(const FrameBuffers& frame, const RenderOptions& options) {
  if (!options.color_bar) return nullptr;
  for (std::size_t i = 0; i < frame.surfaces.size(); ++i) {
    if (i < options.hidden.size() && options.hidden[i]) continue;
    if (!frame.surfaces[i].color_map.empty() && !frame.surfaces[i].indices.empty())
      return &frame.surfaces[i];
  }
  return nullptr;
}

ColorBarLayout LayoutColorBar(int width, int height) {
  const int strip = std::max(90, width / 6);
  ColorBarLayout layout{};
  layout.strip_x0 = width - strip;
  layout.x0 = layout.strip_x0 + strip / 10;
  layout.x1 = layout.x0 + std::max(8, strip / 6);
  layout.y0 = height / 5;
  layout.y1 = height - height / 5;
  layout.label_x = layout.x1 + strip / 20;
  return layout;
}

SurfaceRenderer::SurfaceRenderer(const GlApi& gl) : gl_(gl) {
  const GLuint vs = Compile(gl, GL_VERTEX_SHADER, kVertexShader);
  const GLuint fs = Compile(gl, GL_FRAGMENT_SHADER, kFragmentShader);
  program_ = gl.CreateProgram();
  gl.AttachShader(program_, vs);
  gl.AttachShader(program_, fs);
  gl.LinkProgram(program_);
  gl.DeleteShader(vs);
  gl.DeleteShader(fs);
  GLint ok = 0;
  gl.GetProgramiv(program_, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    gl.GetProgramInfoLog(program_, sizeof log, nullptr, log);
    gl.DeleteProgram(program_);
    throw std::runtime_error(fmt::format("OpenGL program does not link: {}", log));
  }
  u_view_ = gl.GetUniformLocation(program_, "view");
  u_projection_ = gl.GetUniformLocation(program_, "projection");
  u_override_ = gl.GetUniformLocation(program_, "override_color");
  u_use_override_ = gl.GetUniformLocation(program_, "use_override");
  u_ambient_ = gl.GetUniformLocation(program_, "ambient");
  u_point_size_ = gl.GetUniformLocation(program_, "point_size");
}

SurfaceRenderer::~SurfaceRenderer() {
  meshes_.push_back(bar_);
  for (GpuMesh& mesh : meshes_) {
    if (mesh.vao == 0) continue;
    gl_.DeleteBuffers(3, mesh.vbo);
    gl_.DeleteBuffers(1, &mesh.ebo);
    gl_.DeleteVertexArrays(1, &mesh.vao);
  }
  gl_.DeleteProgram(program_);
}

void SurfaceRenderer::Upload(GpuMesh& mesh, const float* positions, const float* normals,
                             const float* colors, std::size_t num_vertices,
                             const std::uint32_t* indices, std::size_t num_indices) {
  if (mesh.vao == 0) {
    gl_.GenVertexArrays(1, &mesh.vao);
    gl_.GenBuffers(3, mesh.vbo);
    gl_.GenBuffers(1, &mesh.ebo);
    gl_.BindVertexArray(mesh.vao);
    for (GLuint a = 0; a < 3; ++a) {
      gl_.BindBuffer(GL_ARRAY_BUFFER, mesh.vbo[a]);
      gl_.VertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
      gl_.EnableVertexAttribArray(a);
    }
    gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, mesh.ebo);
  }
  gl_.BindVertexArray(mesh.vao);
  const float* data[3] = {positions, normals, colors};
  const auto bytes = static_cast<GLsizeiptr>(3 * num_vertices * sizeof(float));
  for (int a = 0; a < 3; ++a) {
    gl_.BindBuffer(GL_ARRAY_BUFFER, mesh.vbo[a]);
    gl_.BufferData(GL_ARRAY_BUFFER, bytes, data[a], GL_STREAM_DRAW);
  }
  gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER,
                 static_cast<GLsizeiptr>(num_indices * sizeof(std::uint32_t)), indices,
                 GL_STREAM_DRAW);
}

void SurfaceRenderer::Draw(const FrameBuffers& frame, const Camera& camera, int width, int height,
                           const RenderOptions& options) {
  const SurfaceBuffers* legend = LegendSurface(frame, options);
  const int scene_width = legend ? LayoutColorBar(width, height).strip_x0 : width;
  gl_.Viewport(0, 0, width, height);
  gl_.ClearColor(options.background.r, options.background.g, options.background.b, 1.0f);
  gl_.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  gl_.Viewport(options.viewport_x, 0, scene_width, height);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_LESS);
  gl_.UseProgram(program_);
  const Eigen::Matrix4f view = camera.View();
  const Eigen::Matrix4f projection = camera.Projection(double(scene_width) / std::max(height, 1));
  gl_.UniformMatrix4fv(u_view_, 1, GL_FALSE, view.data());
  gl_.UniformMatrix4fv(u_projection_, 1, GL_FALSE, projection.data());
  gl_.Uniform1f(u_ambient_, options.lighting ? kAmbient : 1.0f);
  gl_.Enable(GL_PROGRAM_POINT_SIZE);

  if (meshes_.size() < frame.surfaces.size()) meshes_.resize(frame.surfaces.size());
  for (std::size_t i = 0; i < frame.surfaces.size(); ++i) {
    const SurfaceBuffers& s = frame.surfaces[i];
    if (i < options.hidden.size() && options.hidden[i]) continue;
    if (s.indices.empty()) continue;
    Upload(meshes_[i], s.positions.data(), s.normals.data(), s.colors.data(), s.num_vertices(),
           s.indices.data(), s.indices.size());
    const auto count = static_cast<GLsizei>(s.indices.size());
    gl_.Uniform1i(u_use_override_, 0);
    if (s.primitive != Primitive::kTriangles) {
      // Lines and points: unshaded (zero normals), sized in pixels of the final image.
      const float size = std::max(1.0f, s.size * options.pixel_scale);
      if (s.primitive == Primitive::kLines) {
        gl_.LineWidth(size);
        gl_.DrawElements(GL_LINES, count, GL_UNSIGNED_INT, nullptr);
        gl_.LineWidth(1.0f);
      } else {
        gl_.Uniform1f(u_point_size_, size);
        gl_.DrawElements(GL_POINTS, count, GL_UNSIGNED_INT, nullptr);
      }
      continue;
    }
    const bool wireframe =
        options.wireframe || (i < options.edges.size() ? bool(options.edges[i]) : s.wireframe);
    if (wireframe) {
      gl_.Enable(GL_POLYGON_OFFSET_FILL);
      gl_.PolygonOffset(1.0f, 1.0f);
    }
    gl_.DrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
    if (wireframe) {
      gl_.Disable(GL_POLYGON_OFFSET_FILL);
      gl_.PolygonMode(GL_FRONT_AND_BACK, GL_LINE);
      gl_.Uniform1i(u_use_override_, 1);
      gl_.Uniform3f(u_override_, 0.15f, 0.15f, 0.15f);
      gl_.DrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT, nullptr);
      gl_.PolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    }
  }
  if (legend) {
    gl_.Viewport(options.viewport_x, 0, width, height);
    DrawColorBar(*legend, width, height);
  }
  gl_.BindVertexArray(0);
}

void SurfaceRenderer::DrawColorBar(const SurfaceBuffers& surface, int width, int height) {
  // The bar in normalised device coordinates; normals face the viewer, so the colours show
  // unshaded whatever the lighting.
  const ColorMap map = ColorMap::Named(surface.color_map);
  constexpr int kSteps = 64;
  const ColorBarLayout layout = LayoutColorBar(width, height);
  auto ndc_x = [&](int x) { return 2.0f * float(x) / float(width) - 1.0f; };
  auto ndc_y = [&](int y) { return 1.0f - 2.0f * float(y) / float(height); };
  const float x0 = ndc_x(layout.x0), x1 = ndc_x(layout.x1);
  const float y0 = ndc_y(layout.y1), y1 = ndc_y(layout.y0);  // bottom, top
  std::vector<float> positions, normals, colors;
  std::vector<std::uint32_t> indices;
  for (int k = 0; k <= kSteps; ++k) {
    const float s = float(k) / kSteps;
    const Rgb c = map.At(s);
    for (float x : {x0, x1}) {
      positions.insert(positions.end(), {x, y0 + s * (y1 - y0), 0.0f});
      normals.insert(normals.end(), {0.0f, 0.0f, 1.0f});
      colors.insert(colors.end(), {c.r, c.g, c.b});
    }
    if (k < kSteps) {
      const auto b = static_cast<std::uint32_t>(2 * k);
      indices.insert(indices.end(), {b, b + 1, b + 3, b, b + 3, b + 2});
    }
  }
  Upload(bar_, positions.data(), normals.data(), colors.data(), positions.size() / 3,
         indices.data(), indices.size());
  const Eigen::Matrix4f identity = Eigen::Matrix4f::Identity();
  gl_.UniformMatrix4fv(u_view_, 1, GL_FALSE, identity.data());
  gl_.UniformMatrix4fv(u_projection_, 1, GL_FALSE, identity.data());
  gl_.Uniform1i(u_use_override_, 0);
  gl_.Uniform1f(u_ambient_, 1.0f);
  gl_.Disable(GL_DEPTH_TEST);
  gl_.DrawElements(GL_TRIANGLES, static_cast<GLsizei>(indices.size()), GL_UNSIGNED_INT, nullptr);
  gl_.Enable(GL_DEPTH_TEST);
}

}  // namespace gipsi::viz
