#pragma once
/// @file
/// The built-in cardiac cell models and how to create one from JSON. A cell model is described
/// by an object whose "model" key names it and whose other keys are its parameters:
///
///   {"model": "TenTusscherPanfilov2006", "variant": "endo", "g_ks": 0.3}
///   {"model": "AlievPanfilov", "k": 8, "a": 0.15}
///
/// Third parties add models with `CellModels(registry).Register(name, factory, description)`.

#include <functional>
#include <memory>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/core/registry.h"
#include "gipsi/models/ep/cell_model.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Builds a cardiac cell model from its JSON object ({"model": name, ...parameters}); throws
/// InputError naming the JSON path of a bad parameter.
using CellModelFactory = std::function<std::shared_ptr<const CellModel>(const JsonNode& params)>;

/// The cell models by name ("cell model" table of the registry).
inline FactoryTable<CellModelFactory>& CellModels(TypeRegistry& registry) {
  return registry.Table<CellModelFactory>("cell model");
}
inline const FactoryTable<CellModelFactory>& CellModels(const TypeRegistry& registry) {
  return registry.Table<CellModelFactory>("cell model");
}

/// Registers "AlievPanfilov", "MitchellSchaeffer", "FitzHughNagumo", "Nagumo" and
/// "TenTusscherPanfilov2006".
void RegisterCellModels(TypeRegistry& registry);

/// The model described by `node` ({"model": name, ...}). Throws InputError naming the JSON
/// path: no "model" key, an unknown model (the message lists the known ones), an unknown or
/// invalid parameter.
std::shared_ptr<const CellModel> CreateCellModel(const TypeRegistry& registry,
                                                 const JsonNode& node);

}  // namespace gipsi
GIPSI_EXPORT_END
