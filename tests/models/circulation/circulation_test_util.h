#pragma once
// Helpers for the circulation tests: physiological units in SI, and scenes loaded from text.

#include <memory>
#include <string>

#include "gipsi/base/error.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "gipsi/models/circulation/circulation.h"
#include "io/scene_test_util.h"

namespace gipsi {

/// 1 mmHg in Pa (13.5951 g/cm³ · 9.80665 m/s² · 1 mm) and 1 mL in m³.
inline constexpr double kMmHg = 133.322387415;
inline constexpr double kMl = 1e-6;

/// A scene loaded from text, with the registry it needs (kept alive together).
class SceneHolder {
 public:
  explicit SceneHolder(const std::string& text) : registry_(std::make_unique<TypeRegistry>()) {
    RegisterBuiltins(*registry_);
    scene_ = LoadSceneFromString(text, "scene.json", ".", *registry_);
  }
  Circulation& Object(const std::string& name) {
    return dynamic_cast<Circulation&>(scene_.kernel->FindObject(name));
  }
  Scene& scene() { return scene_; }

 private:
  std::unique_ptr<TypeRegistry> registry_;
  Scene scene_;
};

/// The InputError message of loading `text`, or "(no error)".
inline std::string SceneError(const std::string& text) { return testing::SceneLoadError(text); }

}  // namespace gipsi
