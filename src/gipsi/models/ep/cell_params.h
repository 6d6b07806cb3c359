#pragma once
/// @file
/// Reading cell-model parameters from JSON: shared helpers of the model factories. Each throws
/// InputError naming the file and JSON path of the offending value.

#include <string_view>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/models/ep/cell_model.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// node[key], a number strictly between 0 and 1, or `fallback` when absent.
double ReadFraction(const JsonNode& node, std::string_view key, double fallback);

/// node.v_rest and node.v_peak [mV] (each defaulting to `fallback`'s); v_peak must exceed
/// v_rest.
VoltageScale ReadVoltageScale(const JsonNode& node, const VoltageScale& fallback);

}  // namespace gipsi
GIPSI_EXPORT_END
