#include "gipsi/viz/render/gl_api.h"

namespace gipsi::viz {

std::string GlApi::Load(GetProc get_proc) {
#define GIPSI_GL_LOAD(name)                                      \
  name = reinterpret_cast<decltype(name)>(get_proc("gl" #name)); \
  if (name == nullptr) return "gl" #name;
  GIPSI_GL_FUNCTIONS(GIPSI_GL_LOAD)
#undef GIPSI_GL_LOAD
  return "";
}

}  // namespace gipsi::viz
