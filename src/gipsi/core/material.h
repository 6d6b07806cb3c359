#pragma once
/// @file
/// Materials: constitutive laws created by name from scene files ("material": {"law": ...}).
/// Each law belongs to a family (spring laws for mass-spring models; solid laws for FEM, later),
/// and a model asks the registry for a law of the family it understands.

#include <string_view>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Base of every constitutive law. Immutable after construction (shared by all elements).
class Material {
 public:
  virtual ~Material() = default;
  /// The registered law name, e.g. "Hooke".
  [[nodiscard]] virtual std::string_view law() const = 0;
  /// The family of models it serves, e.g. "spring".
  [[nodiscard]] virtual std::string_view family() const = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
