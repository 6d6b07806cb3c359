#pragma once
/// @file
/// The human ventricular myocyte model of ten Tusscher & Panfilov, "Alternans and spiral
/// breakup in a human ventricular tissue model", Am. J. Physiol. Heart Circ. Physiol.
/// 291:H1088–H1100 (2006), building on ten Tusscher, Noble, Noble & Panfilov, Am. J. Physiol.
/// Heart Circ. Physiol. 286:H1573–H1589 (2004). Equations, constants and initial states follow
/// the CellML encodings of the three variants (Physiome Model Repository, P. Noble), which are
/// the usual reference.
///
/// 19 states: V [mV]; Cai, CaSR, CaSS, Nai, Ki [mM]; gates m, h, j, xr1, xr2, xs, r, s, d, f, f2,
/// fCass and the RyR variable R_prime [1]. Currents (µA/µF):
///
///   I_ion = INa + IK1 + Ito + IKr + IKs + ICaL + INaK + INaCa + IpCa + IpK + IbCa + IbNa,
///   dV/dt = −I_ion + I_stim.
///
/// The applied stimulus is carried by K⁺ (dKi/dt includes −I_stim Cm/(Vc F)), as in the CellML
/// model, so that long pacing conserves charge. Variants (the paper's Table 2 and §"Model
/// formulation"): epicardial ("epi": Gks 0.392, Gto 0.294 mS/µF, s-gate with fast recovery),
/// endocardial ("endo": Gto 0.073, s_inf half-point −28 mV, slow s recovery with τ up to
/// 1008 ms) and M cell ("M": Gks 0.098, Gto 0.294, epicardial s-gate).
///
/// Scheme (as in the authors' code): Rush–Larsen (x ← x∞ + (x − x∞) e^(−dt/τ)) for the twelve
/// Hodgkin–Huxley gates m … fCass, forward Euler for V, the concentrations and R_prime; all
/// right-hand sides from the state at the start of the step. Production steps: dt 0.01–0.02 ms.
///
/// Speed (docs/electrophysiology.md): as in CARP/openCARP, what depends on V alone comes from
/// lookup tables over V in [−150, 150] mV, step 0.05 mV, with linear interpolation: the ten
/// gate steady states and the voltage factors of ICaL, INaCa, INaK and IpK (16 columns), and the
/// Rush–Larsen factors e^(−dt/τ) of the eleven voltage-gated gates (11 columns, one table per
/// dt, built by `Prepare(dt)` or the first Step with that dt; up to 8 dt are kept, further ones
/// are evaluated exactly). The IK1 rectification, a function of V − EK, has its own table over
/// [−200, 300] mV. Largest interpolation errors (grid midpoints): 2.1e-5 relative for the
/// voltage terms, 4.5e-5 for IK1, 3.6e-6 absolute for the Rush–Larsen factors at dt 0.01 ms;
/// except within 0.05 mV of −40 mV, where the model's own h and j rates jump. V outside a table
/// reads its end rows. The rest (Nernst potentials, fCass, concentrations) is computed per node
/// with the vectorisable simd::FastExp/FastLog. "lookup_tables": false evaluates every term
/// exactly (std::exp) instead, several times slower: the reference for the table error.

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/json_node.h"
#include "gipsi/models/ep/cell_model.h"
#include "gipsi/models/ep/lookup_table.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

struct TenTusscherPanfilov2006Constants;  // derived from the parameters; internal to the .cc

/// Parameters of TenTusscherPanfilov2006: the variant and the maximal conductances and
/// external concentrations a user most often changes (all other constants are the paper's).
/// Trivially copyable; use `ForVariant` for a variant's defaults.
struct TenTusscherPanfilov2006Params {
  enum class Variant { kEpi, kEndo, kM };
  Variant variant = Variant::kEpi;
  double g_na = 14.838;       ///< INa [mS/µF]
  double g_k1 = 5.405;        ///< IK1 [mS/µF] (scaled by √(Ko/5.4))
  double g_kr = 0.153;        ///< IKr [mS/µF] (scaled by √(Ko/5.4))
  double g_ks = 0.392;        ///< IKs [mS/µF]: 0.392 epi and endo, 0.098 M
  double g_to = 0.294;        ///< Ito [mS/µF]: 0.294 epi and M, 0.073 endo
  double g_cal = 3.98e-5;     ///< ICaL [cm³ µF⁻¹ s⁻¹] (CellML units)
  double g_bna = 2.9e-4;      ///< IbNa [mS/µF]
  double g_bca = 5.92e-4;     ///< IbCa [mS/µF]
  double g_pca = 0.1238;      ///< IpCa maximum [µA/µF]
  double g_pk = 0.0146;       ///< IpK [mS/µF]
  double p_nak = 2.724;       ///< INaK maximum [µA/µF]
  double k_naca = 1000.0;     ///< INaCa maximum [µA/µF]
  double ko = 5.4;            ///< extracellular K⁺ [mM]
  double nao = 140.0;         ///< extracellular Na⁺ [mM]
  double cao = 2.0;           ///< extracellular Ca²⁺ [mM]
  bool lookup_tables = true;  ///< tabulate the voltage terms (see the file comment)
  double table_step = 0.05;   ///< voltage step of the table [mV]

  /// The defaults of `variant` (its g_ks and g_to).
  static TenTusscherPanfilov2006Params ForVariant(Variant variant);
};

/// ten Tusscher–Panfilov 2006 (see the file comment). Immutable apart from its cache of
/// Rush–Larsen tables (thread-safe); shareable between threads. Not copyable or movable.
class TenTusscherPanfilov2006 final : public CellModel {
 public:
  using Params = TenTusscherPanfilov2006Params;
  using Variant = Params::Variant;
  /// Columns of the voltage table (see CalcVoltageTerms).
  static constexpr int kNumVoltageTerms = 16;
  /// Voltage-gated gates with a Rush–Larsen factor table (m h j xr1 xr2 xs r s d f f2).
  static constexpr int kNumVoltageGates = 11;

  explicit TenTusscherPanfilov2006(const Params& params = {});
  ~TenTusscherPanfilov2006() override;
  /// Keys: "variant" ("epi", "endo" or "M"; default "epi"), the fields of Params by name
  /// (non-negative conductances, positive concentrations), "lookup_tables" (bool) and
  /// "table_step" (mV, at most 1). Throws InputError naming the JSON path.
  static std::shared_ptr<const CellModel> FromJson(const JsonNode& node);

  [[nodiscard]] std::string_view type_name() const override { return "TenTusscherPanfilov2006"; }
  [[nodiscard]] std::string_view variant() const override;
  [[nodiscard]] std::string_view scheme() const override {
    return "Rush-Larsen for the gates, forward Euler for V, concentrations and R_prime";
  }
  /// 52 µA/µF for 1 ms, as in the CellML protocol.
  [[nodiscard]] CellStimulus default_stimulus() const override { return {52.0, 1.0}; }
  [[nodiscard]] const Params& params() const { return params_; }
  /// Builds the Rush–Larsen factor table of `dt` (when lookup_tables is on). Thread-safe.
  void Prepare(double dt) const override;

  /// The exact voltage terms at V [mV], kNumVoltageTerms values: the steady states of m, h (= j),
  /// xr1, xr2, xs, r, s, d, f, f2, then ICaL = d f f2 fCass (t[10] CaSS − t[11]), INaCa =
  /// t[12] Nai³ − t[13] Cai, INaK = t[14] Nai/(Nai + 40 mM), IpK = t[15] (V − EK).
  void CalcVoltageTerms(double v, double* terms) const;
  /// The exact rates 1/τ [1/ms] of the kNumVoltageGates gates at V [mV] (m h j xr1 xr2 xs r s
  /// d f f2; for h and j α + β).
  void CalcGateRates(double v, double* rates) const;
  /// The IK1 rectification x∞ = α/(α + β) as a function of V − EK [mV], exactly.
  static double CalcK1Rectification(double v_minus_ek);

  /// The voltage table (kNumVoltageTerms columns), or null when lookup_tables is off.
  [[nodiscard]] const LookupTable* voltage_table() const { return voltage_table_.get(); }
  /// The IK1 rectification table over V − EK, or null when lookup_tables is off.
  [[nodiscard]] const LookupTable* k1_table() const { return k1_table_.get(); }
  /// The table of e^(−dt·rate) for the kNumVoltageGates gates, built on first use; null when
  /// lookup_tables is off or 8 other dt are cached already. Thread-safe.
  [[nodiscard]] const LookupTable* DecayTable(double dt) const;

 protected:
  void DoStep(const CellStateView& states, std::size_t begin, std::size_t end, double dt,
              const double* i_stim) const override;
  void DoCalcIonicCurrent(const ConstCellStateView& states, std::size_t begin, std::size_t end,
                          double* i_ion) const override;

 private:
  struct DecayTableEntry {
    double dt;
    LookupTable table;
  };
  /// Fills the per-node terms of nodes first … first + count − 1 (count ≤ the chunk size): the
  /// voltage terms, EK, the IK1 rectification and, if dt > 0, the Rush–Larsen factors (from
  /// `decay`, or exactly when it is null).
  void FillTerms(const ConstCellStateView& states, std::size_t first, std::size_t count, double dt,
                 const LookupTable* decay, double* terms) const;
  template <bool kStimulus>
  void StepChunk(const CellStateView& states, std::size_t first, std::size_t count, double dt,
                 const double* i_stim, const double* terms) const;

  Params params_;
  std::unique_ptr<const TenTusscherPanfilov2006Constants> constants_;
  std::unique_ptr<const LookupTable> voltage_table_;
  std::unique_ptr<const LookupTable> k1_table_;
  // Cache of Rush–Larsen factor tables by dt: entries are added under the mutex and never
  // removed (steps running in other threads may be reading them); `last_decay_` is the most
  // recently used, checked without locking.
  mutable std::mutex decay_mutex_;
  mutable std::vector<std::unique_ptr<const DecayTableEntry>> decay_tables_;
  mutable std::atomic<const DecayTableEntry*> last_decay_{nullptr};
};

}  // namespace gipsi
GIPSI_EXPORT_END
