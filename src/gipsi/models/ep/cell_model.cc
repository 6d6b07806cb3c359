#include "gipsi/models/ep/cell_model.h"

#include <algorithm>
#include <cmath>

#include "gipsi/base/error.h"

namespace gipsi {

CellStates::CellStates(const CellModel& model, std::size_t num_nodes)
    : num_nodes_(num_nodes),
      num_states_(model.num_states()),
      data_(num_nodes * static_cast<std::size_t>(model.num_states())) {
  for (int k = 0; k < num_states_; ++k)
    std::fill_n(var(k), num_nodes_, model.resting_state()[static_cast<std::size_t>(k)]);
}

std::vector<double> CellStates::Node(std::size_t node) const {
  GIPSI_CHECK(node < num_nodes_, "node {} of {}", node, num_nodes_);
  std::vector<double> values(static_cast<std::size_t>(num_states_));
  for (int k = 0; k < num_states_; ++k) values[static_cast<std::size_t>(k)] = Get(node, k);
  return values;
}

void CellStates::SetNode(std::size_t node, std::span<const double> values) {
  GIPSI_CHECK(node < num_nodes_, "node {} of {}", node, num_nodes_);
  GIPSI_CHECK(values.size() == static_cast<std::size_t>(num_states_), "{} values for {} states",
              values.size(), num_states_);
  for (int k = 0; k < num_states_; ++k) Set(node, k, values[static_cast<std::size_t>(k)]);
}

CellModel::CellModel(std::vector<CellStateInfo> states, std::vector<double> resting, int v_index)
    : states_(std::move(states)), resting_(std::move(resting)), v_index_(v_index) {
  GIPSI_CHECK(!states_.empty() && states_.size() == resting_.size(), "{} states, {} values",
              states_.size(), resting_.size());
  GIPSI_CHECK(v_index_ >= 0 && v_index_ < num_states(), "v_index {}", v_index_);
}

int CellModel::FindState(std::string_view name) const {
  for (int k = 0; k < num_states(); ++k)
    if (states_[static_cast<std::size_t>(k)].name == name) return k;
  return -1;
}

void CellModel::Step(CellStateView states, std::size_t begin, std::size_t end, double dt,
                     std::span<const double> i_stim) const {
  GIPSI_CHECK(states.num_states == num_states(), "{} has {} states, the view {}", type_name(),
              num_states(), states.num_states);
  GIPSI_CHECK(begin <= end && end <= states.num_nodes, "node range [{}, {}) of {}", begin, end,
              states.num_nodes);
  GIPSI_CHECK(dt > 0 && std::isfinite(dt), "dt = {}", dt);
  GIPSI_CHECK(i_stim.empty() || i_stim.size() == states.num_nodes, "{} stimuli for {} nodes",
              i_stim.size(), states.num_nodes);
  if (begin == end) return;
  DoStep(states, begin, end, dt, i_stim.empty() ? nullptr : i_stim.data());
}

void CellModel::CalcIonicCurrent(ConstCellStateView states, std::size_t begin, std::size_t end,
                                 std::span<double> i_ion) const {
  GIPSI_CHECK(states.num_states == num_states(), "{} has {} states, the view {}", type_name(),
              num_states(), states.num_states);
  GIPSI_CHECK(begin <= end && end <= states.num_nodes, "node range [{}, {}) of {}", begin, end,
              states.num_nodes);
  GIPSI_CHECK(i_ion.size() == states.num_nodes, "{} outputs for {} nodes", i_ion.size(),
              states.num_nodes);
  if (begin == end) return;
  DoCalcIonicCurrent(states, begin, end, i_ion.data());
}

}  // namespace gipsi
