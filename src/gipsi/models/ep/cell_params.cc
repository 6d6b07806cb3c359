#include "gipsi/models/ep/cell_params.h"

#include <fmt/format.h>

namespace gipsi {

double ReadFraction(const JsonNode& node, std::string_view key, double fallback) {
  auto child = node.Find(key);
  if (!child) return fallback;
  const double value = child->AsNumber();
  if (!(value > 0.0 && value < 1.0)) child->Expected("a number between 0 and 1 (exclusive)");
  return value;
}

VoltageScale ReadVoltageScale(const JsonNode& node, const VoltageScale& fallback) {
  VoltageScale scale{node.Number("v_rest", fallback.v_rest),
                     node.Number("v_peak", fallback.v_peak)};
  if (!(scale.v_peak > scale.v_rest)) {
    const auto where = node.Find("v_peak");
    const std::string what =
        fmt::format("v_peak ({} mV) must exceed v_rest ({} mV)", scale.v_peak, scale.v_rest);
    if (where) where->Fail(what);
    node.At("v_rest").Fail(what);
  }
  return scale;
}

}  // namespace gipsi
