#pragma once
/// @file
/// Phenomenological cell models: a dimensionless excitation variable u and at most one recovery
/// variable. Each keeps the potential V [mV] as its first state and maps it to
/// u = (V − v_rest)/(v_peak − v_rest) (`VoltageScale`), so a tissue solver diffuses V in mV like
/// for ionic models. With dimensionless-time equations du/dτ = F(u, ·) and t = T τ [ms]:
///
///   I_ion = −(v_peak − v_rest) F / T  [mV/ms = µA/µF],   du/dt = F / T + I_stim/(v_peak − v_rest).
///
/// All use forward Euler for V and the recovery variable, except the Mitchell–Schaeffer gate h,
/// whose equation is linear with piecewise-constant coefficients and is integrated exactly
/// (Rush–Larsen). Parameters are validated when the model is built (see cell_models.h).

#include <memory>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/models/ep/cell_model.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Parameters of AlievPanfilov (defaults: the paper's). Trivially copyable.
struct AlievPanfilovParams {
  double k = 8.0;                   ///< excitation rate (dimensionless)
  double a = 0.15;                  ///< excitation threshold, in (0, 1)
  double epsilon0 = 0.002;          ///< recovery rate far from the u = −μ2 pole
  double mu1 = 0.2;                 ///< ε = ε0 + μ1 v / (u + μ2)
  double mu2 = 0.3;                 ///< must be > 0
  double time_scale = 12.9;         ///< T: ms per dimensionless time unit
  VoltageScale scale{-80.0, 20.0};  ///< V = 100 u − 80 mV
};

/// Aliev & Panfilov, "A simple two-variable model of cardiac excitation", Chaos, Solitons &
/// Fractals 7:293–301 (1996):
///
///   du/dτ = −k u (u − a)(u − 1) − u v,
///   dv/dτ = ε(u, v) (−v − k u (u − a − 1)),   ε(u, v) = ε0 + μ1 v / (u + μ2),
///
/// with t = 12.9 τ ms and V = 100 u − 80 mV. States: V [mV], v [1]; rest V = −80 mV, v = 0.
/// Forward Euler in both; stable and accurate (APD within 0.2 % of a 100× finer step) for
/// dt ≤ 0.1 ms. ε has a pole at u = −μ2 (V = −110 mV by default), reached only with strong
/// hyperpolarising stimuli.
class AlievPanfilov final : public CellModel {
 public:
  explicit AlievPanfilov(const AlievPanfilovParams& params = {});
  /// Reads the keys named like the fields (v_rest, v_peak for `scale`); throws InputError.
  static std::shared_ptr<const CellModel> FromJson(const JsonNode& node);

  [[nodiscard]] std::string_view type_name() const override { return "AlievPanfilov"; }
  [[nodiscard]] std::string_view scheme() const override { return "forward Euler"; }
  [[nodiscard]] CellStimulus default_stimulus() const override { return {50.0, 1.0}; }
  [[nodiscard]] const AlievPanfilovParams& params() const { return params_; }

 protected:
  void DoStep(const CellStateView& states, std::size_t begin, std::size_t end, double dt,
              const double* i_stim) const override;
  void DoCalcIonicCurrent(const ConstCellStateView& states, std::size_t begin, std::size_t end,
                          double* i_ion) const override;

 private:
  template <bool kStimulus>
  void StepRange(const CellStateView& states, std::size_t begin, std::size_t end, double dt,
                 const double* i_stim) const;
  AlievPanfilovParams params_;
};

/// Parameters of MitchellSchaeffer (defaults: the paper's). Trivially copyable.
struct MitchellSchaefferParams {
  double tau_in = 0.3;       ///< ms
  double tau_out = 6.0;      ///< ms
  double tau_open = 120.0;   ///< ms
  double tau_close = 150.0;  ///< ms
  double v_gate = 0.13;      ///< gate switching threshold on u, in (0, 1)
  VoltageScale scale{-80.0, 20.0};
};

/// Mitchell & Schaeffer, "A two-current model for the dynamics of cardiac membrane", Bull.
/// Math. Biol. 65:767–793 (2003), time already in ms:
///
///   du/dt = h u² (1 − u)/τ_in − u/τ_out + J_stim,
///   dh/dt = (1 − h)/τ_open if u < v_gate, −h/τ_close otherwise,
///
/// with V = v_rest + (v_peak − v_rest) u (default −80 / 20 mV; the paper is dimensionless) and
/// J_stim = I_stim / (v_peak − v_rest). States: V [mV], h [1]; rest V = v_rest, h = 1. The
/// maximal APD (from a fully recovered gate) is about τ_close ln(τ_out / (4 τ_in)) ≈ 241 ms.
/// Forward Euler for u; h exactly (Rush–Larsen with the piecewise-constant rates).
class MitchellSchaeffer final : public CellModel {
 public:
  explicit MitchellSchaeffer(const MitchellSchaefferParams& params = {});
  /// Reads the keys named like the fields (v_rest, v_peak for `scale`); throws InputError.
  static std::shared_ptr<const CellModel> FromJson(const JsonNode& node);

  [[nodiscard]] std::string_view type_name() const override { return "MitchellSchaeffer"; }
  [[nodiscard]] std::string_view scheme() const override {
    return "forward Euler for V, exact exponential (Rush-Larsen) for h";
  }
  [[nodiscard]] CellStimulus default_stimulus() const override { return {50.0, 1.0}; }
  [[nodiscard]] const MitchellSchaefferParams& params() const { return params_; }

 protected:
  void DoStep(const CellStateView& states, std::size_t begin, std::size_t end, double dt,
              const double* i_stim) const override;
  void DoCalcIonicCurrent(const ConstCellStateView& states, std::size_t begin, std::size_t end,
                          double* i_ion) const override;

 private:
  template <bool kStimulus>
  void StepRange(const CellStateView& states, std::size_t begin, std::size_t end, double dt,
                 const double* i_stim) const;
  MitchellSchaefferParams params_;
};

/// Parameters of FitzHughNagumo and Nagumo (defaults: Sundnes et al. 2006, §2.4.1). Trivially
/// copyable.
struct FitzHughNagumoParams {
  double a = 0.13;   ///< excitation threshold on u, in (0, 1)
  double b = 0.013;  ///< recovery rate [1/ms]
  double c1 = 0.26;  ///< excitation rate [1/ms] (k of the Nagumo equation)
  double c2 = 0.1;   ///< recovery coupling [1/ms]
  double c3 = 1.0;   ///< recovery decay (dimensionless)
  VoltageScale scale{-85.0, 40.0};
};

/// The FitzHugh–Nagumo model in the cardiac form of Rogers & McCulloch (IEEE Trans. Biomed.
/// Eng. 41:743, 1994), as reparametrised in Sundnes et al., "Computing the Electrical Activity
/// in the Heart", Springer 2006, §2.4.1 (time in ms):
///
///   du/dt = c1 u (u − a)(1 − u) − c2 u w + I_stim/(v_peak − v_rest),
///   dw/dt = b (u − c3 w),
///
/// with V = v_rest + (v_peak − v_rest) u (default −85 / 40 mV). States: V [mV], w [1]; rest
/// V = v_rest, w = 0.
///
/// Without recovery ("Nagumo", `with_recovery` false, state V only) it is the bistable Nagumo
/// equation u_t = k u (1 − u)(u − a) with k = c1: u = 0 and u = 1 are stable, a is the
/// threshold. With v_rest = 0 and v_peak = 1 the state V is u itself (bit for bit), for the
/// travelling-front test u = 1/(1 + exp((x − c t)/√(2D/k))), c = √(kD/2)(1 − 2a).
/// Forward Euler for every state.
class FitzHughNagumo final : public CellModel {
 public:
  explicit FitzHughNagumo(const FitzHughNagumoParams& params = {}, bool with_recovery = true);
  /// "FitzHughNagumo" keys: a, b, c1, c2, c3, v_rest, v_peak; "Nagumo" keys: k (= c1), a,
  /// v_rest, v_peak. Throws InputError.
  static std::shared_ptr<const CellModel> FromJson(const JsonNode& node, bool with_recovery);

  [[nodiscard]] std::string_view type_name() const override {
    return with_recovery_ ? "FitzHughNagumo" : "Nagumo";
  }
  [[nodiscard]] std::string_view scheme() const override { return "forward Euler"; }
  [[nodiscard]] CellStimulus default_stimulus() const override {
    return {0.4 * params_.scale.amplitude(), 1.0};
  }
  [[nodiscard]] const FitzHughNagumoParams& params() const { return params_; }
  [[nodiscard]] bool with_recovery() const { return with_recovery_; }

 protected:
  void DoStep(const CellStateView& states, std::size_t begin, std::size_t end, double dt,
              const double* i_stim) const override;
  void DoCalcIonicCurrent(const ConstCellStateView& states, std::size_t begin, std::size_t end,
                          double* i_ion) const override;

 private:
  template <bool kStimulus, bool kRecovery>
  void StepRange(const CellStateView& states, std::size_t begin, std::size_t end, double dt,
                 const double* i_stim) const;
  FitzHughNagumoParams params_;
  bool with_recovery_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
