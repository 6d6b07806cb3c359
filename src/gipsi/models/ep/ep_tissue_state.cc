/// @file
/// EpTissue after a restore (Monodomain and GridMonodomain): the state is EpState (every cell
/// state variable of every node and the activation/APD tracking), bound with BindState, so
/// checkpoints and snapshots need no code here beyond what derives from the state; and the
/// state as per-node rows (EpState::ToRows), which a split monodomain's checkpoint moves to
/// another partition.

#include "gipsi/models/ep/ep_tissue.h"

#include "gipsi/base/error.h"

namespace gipsi {

EpState EpState::Sized(const CellModel& cell, std::size_t num_nodes) {
  EpState s;
  s.cells = CellStates(cell, num_nodes);
  const auto n = static_cast<Index>(num_nodes);
  s.activation_time = VecX::Constant(n, -1);
  s.last_activation = VecX::Constant(n, -1);
  s.apd = VecX::Constant(n, -1);
  s.v_min = VecX::Zero(n);
  s.v_peak = VecX::Zero(n);
  s.depolarised.assign(num_nodes, 0);
  return s;
}

std::vector<double> EpState::ToRows() const {
  const std::size_t n = cells.num_nodes();
  const int k = cells.num_states();
  const std::size_t width = static_cast<std::size_t>(k) + 6;
  std::vector<double> rows(n * width);
  for (std::size_t i = 0; i < n; ++i) {
    double* row = rows.data() + i * width;
    for (int j = 0; j < k; ++j) row[j] = cells.var(j)[i];
    const auto node = static_cast<Index>(i);
    row[k] = activation_time[node];
    row[k + 1] = last_activation[node];
    row[k + 2] = apd[node];
    row[k + 3] = v_min[node];
    row[k + 4] = v_peak[node];
    row[k + 5] = depolarised[i] != 0 ? 1.0 : 0.0;
  }
  return rows;
}

void EpState::FromRows(std::span<const double> rows) {
  const std::size_t n = cells.num_nodes();
  const int k = cells.num_states();
  const std::size_t width = static_cast<std::size_t>(k) + 6;
  GIPSI_CHECK(rows.size() == n * width, "EpState::FromRows: {} values for {} nodes of {}",
              rows.size(), n, width);
  for (std::size_t i = 0; i < n; ++i) {
    const double* row = rows.data() + i * width;
    for (int j = 0; j < k; ++j) cells.var(j)[i] = row[j];
    const auto node = static_cast<Index>(i);
    activation_time[node] = row[k];
    last_activation[node] = row[k + 1];
    apd[node] = row[k + 2];
    v_min[node] = row[k + 3];
    v_peak[node] = row[k + 4];
    depolarised[i] = row[k + 5] != 0 ? 1 : 0;
  }
}

void EpTissue::StateRestored() { v_prev_ = voltage(); }

}  // namespace gipsi
