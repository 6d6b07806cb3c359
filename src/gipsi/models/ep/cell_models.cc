#include "gipsi/models/ep/cell_models.h"

#include "gipsi/base/error.h"
#include "gipsi/models/ep/phenomenological.h"
#include "gipsi/models/ep/ten_tusscher_panfilov_2006.h"

namespace gipsi {

void RegisterCellModels(TypeRegistry& registry) {
  CellModels(registry).Register("AlievPanfilov", &AlievPanfilov::FromJson,
                                "two-variable phenomenological ventricular model (1996)");
  CellModels(registry).Register("MitchellSchaeffer", &MitchellSchaeffer::FromJson,
                                "two-current phenomenological model with one gate (2003)");
  CellModels(registry).Register(
      "FitzHughNagumo", [](const JsonNode& node) { return FitzHughNagumo::FromJson(node, true); },
      "cubic excitation with linear recovery (Rogers-McCulloch form)");
  CellModels(registry).Register(
      "Nagumo", [](const JsonNode& node) { return FitzHughNagumo::FromJson(node, false); },
      "bistable cubic u' = k u (1 - u)(u - a), no recovery");
  CellModels(registry).Register("TenTusscherPanfilov2006", &TenTusscherPanfilov2006::FromJson,
                                "human ventricular ionic model, variants epi, endo, M (2006)");
}

std::shared_ptr<const CellModel> CreateCellModel(const TypeRegistry& registry,
                                                 const JsonNode& node) {
  if (!node.is_object()) node.Expected("an object with a \"model\" key");
  const JsonNode name = node.At("model");
  auto model = CellModels(registry).Get(name.AsString(), name)(node);
  GIPSI_CHECK(model != nullptr, "factory for '{}' returned null", name.AsString());
  return model;
}

}  // namespace gipsi
