#pragma once
/// @file
/// `GlApi`: the OpenGL 3.3 core functions the renderers use, as pointers loaded from whichever
/// context is current (OSMesa off screen, GLFW on screen). Calling through a table instead of
/// linking libGL keeps the software (OSMesa) and windowed (libGL via GLFW) implementations,
/// which export the same symbol names, from shadowing each other in one process.

#define GL_GLEXT_PROTOTYPES 1  // prototypes only to name the pointer types (decltype)
#include <GL/gl.h>
#include <GL/glext.h>

#include <string>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi::viz {

// clang-format off
#define GIPSI_GL_FUNCTIONS(X) \
  X(AttachShader) X(BindBuffer) X(BindFramebuffer) X(BindRenderbuffer) \
  X(BindVertexArray) X(BlendFunc) X(BlitFramebuffer) X(BufferData) \
  X(CheckFramebufferStatus) X(Clear) X(ClearColor) X(CompileShader) \
  X(CreateProgram) X(CreateShader) X(DeleteBuffers) X(DeleteFramebuffers) \
  X(DeleteProgram) X(DeleteRenderbuffers) X(DeleteShader) X(DeleteVertexArrays) \
  X(DepthFunc) X(Disable) X(DrawArrays) X(DrawElements) X(Enable) \
  X(EnableVertexAttribArray) X(Finish) X(FramebufferRenderbuffer) X(GenBuffers) \
  X(GenFramebuffers) X(GenRenderbuffers) X(GenVertexArrays) X(GetError) \
  X(GetIntegerv) X(GetProgramInfoLog) X(GetProgramiv) X(GetShaderInfoLog) \
  X(GetShaderiv) X(GetString) X(GetUniformLocation) X(LineWidth) X(LinkProgram) \
  X(PixelStorei) \
  X(PolygonMode) X(PolygonOffset) X(ReadPixels) X(RenderbufferStorage) \
  X(ShaderSource) X(Uniform1f) X(Uniform1i) X(Uniform3f) X(UniformMatrix4fv) \
  X(UseProgram) X(VertexAttribPointer) X(Viewport)
// clang-format on

/// Pointers to the GL functions above, named without the `gl` prefix (`gl.Clear(...)`).
/// Copyable (a table of plain pointers).
struct GlApi {
#define GIPSI_GL_MEMBER(name) decltype(&::gl##name) name = nullptr;
  GIPSI_GL_FUNCTIONS(GIPSI_GL_MEMBER)
#undef GIPSI_GL_MEMBER

  /// Loads every function through `get_proc` (e.g. OSMesaGetProcAddress, glfwGetProcAddress)
  /// with a current context. Returns the name of the first function it could not find, or ""
  /// when all were found.
  using GetProc = void* (*)(const char* name);
  std::string Load(GetProc get_proc);
};

}  // namespace gipsi::viz
GIPSI_EXPORT_END
