#pragma once
/// @file
/// Cardiac cell models: the reaction part of the monodomain equation
///
///   χ (Cm ∂V/∂t + I_ion(V, s)) = ∇·(σ∇V) + I_stim,vol,    ds/dt = g(V, s),
///
/// i.e. per node dV/dt = −I_ion + I_stim and the model's own state equations. A `CellModel` is
/// an immutable description (parameters, lookup tables) shared by every node; the states live
/// outside it in structure-of-arrays form (`CellStates`, `CellStateView`), so one object advances
/// any number of nodes and a solver can split the nodes among threads.
///
/// Units (see docs/electrophysiology.md): time ms; voltage mV; I_ion and I_stim are currents per
/// unit membrane capacitance in µA/µF, which equals mV/ms. I_stim is an applied (injected)
/// current: a positive stimulus depolarises (dV/dt = −I_ion + I_stim). Concentrations are in mM;
/// gates and other dimensionless states have unit "1". Phenomenological models keep V in mV as
/// their state and map it to their dimensionless variable with documented scales.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/state_value.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class CellModel;

/// Name and unit of one state variable, e.g. {"Cai", "mM"}. Copyable.
struct CellStateInfo {
  std::string name;  ///< as in the model's paper, e.g. "V", "xr1", "CaSS"
  std::string unit;  ///< "mV", "mM", or "1" for dimensionless states
};

/// Read-only view of the states of `num_nodes` cells, structure of arrays: state variable k of
/// node i is `data[k * num_nodes + i]`. Cheap to copy; refers to storage it does not own.
struct ConstCellStateView {
  const double* data = nullptr;
  std::size_t num_nodes = 0;  ///< number of cells; also the stride between state variables
  int num_states = 0;
  /// The contiguous array (num_nodes values) of state variable k.
  [[nodiscard]] const double* var(int k) const {
    return data + static_cast<std::size_t>(k) * num_nodes;
  }
};

/// Mutable view of cell states; layout as ConstCellStateView. Cheap to copy; not owning.
struct CellStateView {
  double* data = nullptr;
  std::size_t num_nodes = 0;  ///< number of cells; also the stride between state variables
  int num_states = 0;
  /// The contiguous array (num_nodes values) of state variable k.
  [[nodiscard]] double* var(int k) const { return data + static_cast<std::size_t>(k) * num_nodes; }
  operator ConstCellStateView() const { return {data, num_nodes, num_states}; }  // NOLINT
};

/// Owning storage for the states of `num_nodes` cells of one model, structure of arrays (one
/// contiguous array per state variable). Copyable and movable.
class CellStates {
 public:
  /// No cells (a placeholder until the owner knows its model and size).
  CellStates() = default;
  /// `num_nodes` cells, each in `model`'s resting state.
  CellStates(const CellModel& model, std::size_t num_nodes);

  [[nodiscard]] std::size_t num_nodes() const { return num_nodes_; }
  [[nodiscard]] int num_states() const { return num_states_; }
  [[nodiscard]] CellStateView view() { return {data_.data(), num_nodes_, num_states_}; }
  [[nodiscard]] ConstCellStateView view() const { return {data_.data(), num_nodes_, num_states_}; }
  /// The array of state variable k (num_nodes values).
  [[nodiscard]] double* var(int k) { return view().var(k); }
  [[nodiscard]] const double* var(int k) const { return view().var(k); }
  /// State variable k of `node`.
  [[nodiscard]] double Get(std::size_t node, int k) const { return var(k)[node]; }
  void Set(std::size_t node, int k, double value) { var(k)[node] = value; }
  /// All state variables of `node`, in the model's order.
  [[nodiscard]] std::vector<double> Node(std::size_t node) const;
  /// Sets all state variables of `node`; `values` has num_states() entries.
  void SetNode(std::size_t node, std::span<const double> values);

  /// State value fields (gipsi/base/state_value.h): the sizes (checked on reading) and every
  /// variable of every cell.
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("num_nodes", s.num_nodes_, Shape::kFixed);
    v("num_states", s.num_states_, Shape::kFixed);
    v("values", s.data_, Shape::kFixed);
  }

 private:
  std::size_t num_nodes_ = 0;
  int num_states_ = 0;
  std::vector<double> data_;
};

/// Default stimulus of a model: suprathreshold from its resting state. Copyable.
struct CellStimulus {
  double amplitude = 0;  ///< µA/µF (= mV/ms), positive depolarises
  double duration = 0;   ///< ms
};

/// Base of every cell model. Immutable after construction and safe to share between threads:
/// `Step` and `CalcIonicCurrent` on disjoint node ranges may run concurrently. Not copyable or
/// movable (use it through `std::shared_ptr<const CellModel>`).
///
/// Public methods check their arguments (always on; a violation aborts as a programmer error)
/// and call the protected `Do…` hooks. Nothing in a step throws; after `Prepare(dt)` nothing
/// in a step of that dt allocates. A diverging cell shows as non-finite states, which the owner
/// (a tissue solver) checks.
class CellModel {
 public:
  virtual ~CellModel() = default;
  CellModel(const CellModel&) = delete;
  CellModel& operator=(const CellModel&) = delete;

  /// The registered model name, e.g. "TenTusscherPanfilov2006".
  [[nodiscard]] virtual std::string_view type_name() const = 0;
  /// The variant, e.g. "epi", or "" for models without variants.
  [[nodiscard]] virtual std::string_view variant() const { return ""; }
  /// One line naming the time-stepping scheme of `Step`.
  [[nodiscard]] virtual std::string_view scheme() const = 0;
  /// A suprathreshold stimulus from rest (used by `gipsi cell` when none is given).
  [[nodiscard]] virtual CellStimulus default_stimulus() const = 0;

  [[nodiscard]] int num_states() const { return static_cast<int>(states_.size()); }
  /// Names and units of the state variables, in storage order.
  [[nodiscard]] const std::vector<CellStateInfo>& states() const { return states_; }
  /// Index of the transmembrane voltage V [mV] among the states.
  [[nodiscard]] int v_index() const { return v_index_; }
  /// Index of the state called `name`, or -1.
  [[nodiscard]] int FindState(std::string_view name) const;
  /// The resting initial state (num_states() values), e.g. the published initial values.
  [[nodiscard]] const std::vector<double>& resting_state() const { return resting_; }

  /// Precomputes what steps of `dt` [ms] need (e.g. tables of Rush–Larsen factors), so that
  /// the first Step with that dt does not have to. Optional: Step prepares on first use. Safe
  /// to call concurrently; the default does nothing.
  virtual void Prepare(double dt) const { (void)dt; }

  /// Advances nodes [begin, end) of `states` by `dt` [ms] with the model's scheme, the
  /// stimulus `i_stim[i]` [µA/µF] held constant over the step. `i_stim` is indexed like the
  /// nodes (size states.num_nodes) or empty for no stimulus. Preconditions (abort otherwise):
  /// the view has num_states() variables, begin ≤ end ≤ num_nodes, 0 < dt < inf. The result
  /// for a node depends only on that node's states, never on the range it was stepped in.
  void Step(CellStateView states, std::size_t begin, std::size_t end, double dt,
            std::span<const double> i_stim = {}) const;

  /// I_ion [µA/µF] of nodes [begin, end) into `i_ion[i]` (indexed like the nodes, size
  /// states.num_nodes): the current the forward-Euler voltage update of `Step` uses, so
  /// V + dt (−I_ion + I_stim) is the stepped V. Same preconditions as Step.
  void CalcIonicCurrent(ConstCellStateView states, std::size_t begin, std::size_t end,
                        std::span<double> i_ion) const;

 protected:
  /// `states`: names and units; `resting`: one value per state; `v_index`: where V is.
  CellModel(std::vector<CellStateInfo> states, std::vector<double> resting, int v_index);

  /// Step with checked arguments; `i_stim` is null for no stimulus.
  virtual void DoStep(const CellStateView& states, std::size_t begin, std::size_t end, double dt,
                      const double* i_stim) const = 0;
  /// CalcIonicCurrent with checked arguments.
  virtual void DoCalcIonicCurrent(const ConstCellStateView& states, std::size_t begin,
                                  std::size_t end, double* i_ion) const = 0;

 private:
  std::vector<CellStateInfo> states_;
  std::vector<double> resting_;
  int v_index_;
};

/// Maps a phenomenological model's dimensionless potential u to V [mV]:
/// V = v_rest + (v_peak − v_rest) u. Trivially copyable.
struct VoltageScale {
  double v_rest = -80.0;  ///< V at u = 0 [mV]
  double v_peak = 20.0;   ///< V at u = 1 [mV]
  [[nodiscard]] double amplitude() const { return v_peak - v_rest; }
  [[nodiscard]] double ToU(double v) const { return (v - v_rest) / (v_peak - v_rest); }
  [[nodiscard]] double ToV(double u) const { return v_rest + (v_peak - v_rest) * u; }
};

}  // namespace gipsi
GIPSI_EXPORT_END
