#pragma once
// Helpers shared by the cell-model tests.

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "gipsi/base/json_node.h"
#include "gipsi/models/ep/cell_models.h"
#include "gipsi/models/ep/single_cell.h"

namespace gipsi::testing {

/// The model described by `json` ({"model": ..., ...}), built through the registry.
inline std::shared_ptr<const CellModel> MakeCellModel(const std::string& json) {
  TypeRegistry registry;
  RegisterCellModels(registry);
  JsonDocument doc = JsonDocument::Parse(json, "test.json");
  return CreateCellModel(registry, doc.root());
}

/// Paces `model` with its default stimulus at bcl 1000 ms.
inline SingleCellResult Pace(const CellModel& model, double dt, int beats,
                             std::int64_t record_every = 0, double bcl = 1000.0) {
  PacingProtocol protocol;
  protocol.dt = dt;
  protocol.beats = beats;
  protocol.bcl = bcl;
  protocol.stim_amplitude = model.default_stimulus().amplitude;
  protocol.stim_duration = model.default_stimulus().duration;
  protocol.record_every = record_every;
  return PaceSingleCell(model, protocol);
}

/// Root mean square of a − b (same lengths).
inline double RmsDifference(const std::vector<double>& a, const std::vector<double>& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(sum / static_cast<double>(a.size()));
}

}  // namespace gipsi::testing
