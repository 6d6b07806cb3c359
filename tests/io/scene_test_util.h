#pragma once
// Shared by tests that load scenes from text: the error a scene raises.

#include <string>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"

namespace gipsi::testing {

/// The InputError message of loading `text` (named "scene.json") with the built-in types, or
/// "(no error)".
inline std::string SceneLoadError(const std::string& text) {
  TypeRegistry registry;
  RegisterBuiltins(registry);
  try {
    (void)LoadSceneFromString(text, "scene.json", ".", registry);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace gipsi::testing
