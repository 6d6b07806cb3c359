#include "gipsi/models/ep/ten_tusscher_panfilov_2006.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/models/ep/simd_math.h"

namespace gipsi {

namespace {

using Variant = TenTusscherPanfilov2006Params::Variant;

// Physical constants and cell geometry (CellML / the authors' code).
constexpr double kGasConstant = 8314.472;  // mJ/(mol K)
constexpr double kTemperature = 310.0;     // K
constexpr double kFaraday = 96485.3415;    // C/mol
constexpr double kCm = 0.185;              // µF
constexpr double kVc = 0.016404;           // µL, cytoplasm
constexpr double kVsr = 0.001094;          // µL, sarcoplasmic reticulum
constexpr double kVss = 0.00005468;        // µL, dyadic subspace

// Fixed current parameters.
constexpr double kPKNa = 0.03;       // relative Na⁺ permeability of IKs
constexpr double kKmK = 1.0;         // mM, INaK
constexpr double kKmNa = 40.0;       // mM, INaK
constexpr double kKmNai = 87.5;      // mM, INaCa
constexpr double kKmCa = 1.38;       // mM, INaCa
constexpr double kKsat = 0.1;        // INaCa saturation
constexpr double kNaCaAlpha = 2.5;   // INaCa enhancement factor
constexpr double kNaCaGamma = 0.35;  // INaCa voltage dependence
constexpr double kKpCa = 0.0005;     // mM, IpCa

// Calcium dynamics.
constexpr double kK1Prime = 0.15;   // 1/(mM² ms)
constexpr double kK2Prime = 0.045;  // 1/(mM ms)
constexpr double kK3 = 0.06;        // 1/ms
constexpr double kK4 = 0.005;       // 1/ms
constexpr double kEC = 1.5;         // mM
constexpr double kMaxSR = 2.5;
constexpr double kMinSR = 1.0;
constexpr double kVrel = 0.102;       // 1/ms
constexpr double kVleak = 0.00036;    // 1/ms
constexpr double kVxfer = 0.0038;     // 1/ms
constexpr double kVmaxUp = 0.006375;  // mM/ms
constexpr double kKup = 0.00025;      // mM
constexpr double kBufC = 0.2;         // mM
constexpr double kKBufC = 0.001;      // mM
constexpr double kBufSR = 10.0;       // mM
constexpr double kKBufSR = 0.3;       // mM
constexpr double kBufSS = 0.4;        // mM
constexpr double kKBufSS = 0.00025;   // mM

// Table range.
constexpr double kTableVMin = -150.0;  // mV
constexpr double kTableVMax = 150.0;   // mV

// Nodes per chunk: the voltage terms of a chunk live in a stack buffer (27 × 64 doubles).
constexpr std::size_t kChunk = 64;

enum State : int {
  kV,
  kCai,
  kCaSR,
  kCaSS,
  kNai,
  kKi,
  kM,
  kH,
  kJ,
  kXr1,
  kXr2,
  kXs,
  kR,
  kS,
  kD,
  kF,
  kF2,
  kFCass,
  kRPrime,
  kNumStates
};

// Per-node terms of a chunk, each a row of kChunk values in the terms buffer.
enum Term : int {
  // The voltage table's columns (CalcVoltageTerms).
  kMInf,
  kHJInf,
  kXr1Inf,
  kXr2Inf,
  kXsInf,
  kRInf,
  kSInf,
  kDInf,
  kFInf,
  kF2Inf,
  kCaLCaSS,  // ICaL = d f f2 fCass (term · CaSS − kCaLCao term)
  kCaLCao,
  kNaCaNai,  // INaCa = term · Nai³ − kNaCaCai term · Cai
  kNaCaCai,
  kNaK,  // INaK = term · Nai / (Nai + KmNa)
  kPK,   // IpK = term · (V − EK)
  // Rush–Larsen factors e^(−dt/τ) (CalcGateRates order).
  kMDecay,
  kHDecay,
  kJDecay,
  kXr1Decay,
  kXr2Decay,
  kXsDecay,
  kRDecay,
  kSDecay,
  kDDecay,
  kFDecay,
  kF2Decay,
  // Per node: the K⁺ Nernst potential and the IK1 rectification at V − EK.
  kEK,
  kK1Rect,
  kNumTerms
};
static_assert(kMDecay == TenTusscherPanfilov2006::kNumVoltageTerms);
static_assert(kEK - kMDecay == TenTusscherPanfilov2006::kNumVoltageGates);

// IK1 table range over V − EK [mV].
constexpr double kK1TableMin = -200.0;
constexpr double kK1TableMax = 300.0;
// Rush–Larsen tables kept (distinct dt).
constexpr std::size_t kMaxDecayTables = 8;

std::vector<CellStateInfo> StateInfo() {
  return {{"V", "mV"},  {"Cai", "mM"}, {"CaSR", "mM"}, {"CaSS", "mM"},  {"Nai", "mM"},
          {"Ki", "mM"}, {"m", "1"},    {"h", "1"},     {"j", "1"},      {"xr1", "1"},
          {"xr2", "1"}, {"xs", "1"},   {"r", "1"},     {"s", "1"},      {"d", "1"},
          {"f", "1"},   {"f2", "1"},   {"fCass", "1"}, {"R_prime", "1"}};
}

/// The CellML initial values of each variant (a paced cell at the end of diastole).
std::vector<double> RestingState(Variant variant) {
  switch (variant) {
    case Variant::kEndo:
      return {-86.709,  0.00013, 3.715,   0.00036, 10.355, 138.4,    0.00155,
              0.7573,   0.7225,  0.00448, 0.476,   0.0087, 2.235e-8, 0.3212,
              3.164e-5, 0.8009,  0.9778,  0.9953,  0.9068};
    case Variant::kM:
      return {-85.423,  0.000153, 4.272,  0.00042, 10.132, 138.52,   0.00165,
              0.749,    0.6788,   0.0165, 0.473,   0.0174, 2.347e-8, 0.999998,
              3.288e-5, 0.7026,   0.9526, 0.9942,  0.8978};
    case Variant::kEpi:
      break;
  }
  return {-85.23, 0.000126, 3.64,    0.00036,  8.604,    136.89, 0.00172, 0.7444, 0.7045, 0.00621,
          0.4712, 0.0095,   2.42e-8, 0.999998, 3.373e-5, 0.7888, 0.9755,  0.9953, 0.9073};
}

/// 1 / (1 + e^x).
inline double Sigmoid(double x) { return 1.0 / (1.0 + std::exp(x)); }

/// x / (e^x − 1), continuous at 0.
inline double XOverExpm1(double x) {
  if (std::abs(x) < 1e-12) return 1.0 - 0.5 * x;
  return x / std::expm1(x);
}

}  // namespace

/// Constants derived from the parameters once. Trivially copyable (copied into the kernels).
struct TenTusscherPanfilov2006Constants {
  double rtf;                                    // RT/F [mV]
  double log_nao, log_ko, log_cao, log_eks_num;  // logarithms of the Nernst numerators
  double g_na, g_k1, g_kr, g_ks, g_to, g_bna, g_bca, g_pca;
  double cm_vc_f;    // Cm / (Vc F): µA/µF → mM/ms in the cytoplasm
  double cm_2vc_f;   // Cm / (2 Vc F)
  double cm_2vss_f;  // Cm / (2 Vss F)
  double vsr_vc, vsr_vss, vc_vss;
};

TenTusscherPanfilov2006Params TenTusscherPanfilov2006Params::ForVariant(Variant variant) {
  TenTusscherPanfilov2006Params p;
  p.variant = variant;
  p.g_ks = variant == Variant::kM ? 0.098 : 0.392;
  p.g_to = variant == Variant::kEndo ? 0.073 : 0.294;
  return p;
}

TenTusscherPanfilov2006::TenTusscherPanfilov2006(const Params& params)
    : CellModel(StateInfo(), RestingState(params.variant), kV), params_(params) {
  GIPSI_CHECK(params.ko > 0 && params.nao > 0 && params.cao > 0, "non-positive concentration");
  TenTusscherPanfilov2006Constants c{};
  c.rtf = kGasConstant * kTemperature / kFaraday;
  c.log_nao = std::log(params.nao);
  c.log_ko = std::log(params.ko);
  c.log_cao = std::log(params.cao);
  c.log_eks_num = std::log(params.ko + kPKNa * params.nao);
  const double ko_factor = std::sqrt(params.ko / 5.4);
  c.g_na = params.g_na;
  c.g_k1 = params.g_k1 * ko_factor;
  c.g_kr = params.g_kr * ko_factor;
  c.g_ks = params.g_ks;
  c.g_to = params.g_to;
  c.g_bna = params.g_bna;
  c.g_bca = params.g_bca;
  c.g_pca = params.g_pca;
  c.cm_vc_f = kCm / (kVc * kFaraday);
  c.cm_2vc_f = kCm / (2.0 * kVc * kFaraday);
  c.cm_2vss_f = kCm / (2.0 * kVss * kFaraday);
  c.vsr_vc = kVsr / kVc;
  c.vsr_vss = kVsr / kVss;
  c.vc_vss = kVc / kVss;
  constants_ = std::make_unique<const TenTusscherPanfilov2006Constants>(c);
  if (params.lookup_tables) {
    GIPSI_CHECK(params.table_step > 0 && params.table_step <= 1.0, "table step {} mV",
                params.table_step);
    voltage_table_ = std::make_unique<const LookupTable>(
        kTableVMin, kTableVMax, params.table_step, kNumVoltageTerms,
        [this](double v, double* row) { CalcVoltageTerms(v, row); });
    k1_table_ = std::make_unique<const LookupTable>(
        kK1TableMin, kK1TableMax, params.table_step, 1,
        [](double dk, double* row) { row[0] = CalcK1Rectification(dk); });
  }
}

TenTusscherPanfilov2006::~TenTusscherPanfilov2006() = default;

std::string_view TenTusscherPanfilov2006::variant() const {
  switch (params_.variant) {
    case Variant::kEndo:
      return "endo";
    case Variant::kM:
      return "M";
    case Variant::kEpi:
      break;
  }
  return "epi";
}

std::shared_ptr<const CellModel> TenTusscherPanfilov2006::FromJson(const JsonNode& node) {
  node.CheckKeys({"model", "variant", "g_na", "g_k1", "g_kr", "g_ks", "g_to", "g_cal", "g_bna",
                  "g_bca", "g_pca", "g_pk", "p_nak", "k_naca", "ko", "nao", "cao", "lookup_tables",
                  "table_step"});
  Variant variant = Variant::kEpi;
  if (auto v = node.Find("variant")) {
    const std::string name = v->AsChoice({"epi", "endo", "M"});
    variant = name == "endo" ? Variant::kEndo : name == "M" ? Variant::kM : Variant::kEpi;
  }
  Params p = Params::ForVariant(variant);
  p.g_na = node.NonNegative("g_na", p.g_na);
  p.g_k1 = node.NonNegative("g_k1", p.g_k1);
  p.g_kr = node.NonNegative("g_kr", p.g_kr);
  p.g_ks = node.NonNegative("g_ks", p.g_ks);
  p.g_to = node.NonNegative("g_to", p.g_to);
  p.g_cal = node.NonNegative("g_cal", p.g_cal);
  p.g_bna = node.NonNegative("g_bna", p.g_bna);
  p.g_bca = node.NonNegative("g_bca", p.g_bca);
  p.g_pca = node.NonNegative("g_pca", p.g_pca);
  p.g_pk = node.NonNegative("g_pk", p.g_pk);
  p.p_nak = node.NonNegative("p_nak", p.p_nak);
  p.k_naca = node.NonNegative("k_naca", p.k_naca);
  p.ko = node.Positive("ko", p.ko);
  p.nao = node.Positive("nao", p.nao);
  p.cao = node.Positive("cao", p.cao);
  p.lookup_tables = node.Bool("lookup_tables", p.lookup_tables);
  p.table_step = node.Positive("table_step", p.table_step);
  if (p.table_step > 1.0) node.At("table_step").Expected("a step of at most 1 mV");
  return std::make_shared<TenTusscherPanfilov2006>(p);
}

void TenTusscherPanfilov2006::CalcVoltageTerms(double v, double* terms) const {
  const Params& p = params_;
  const double rtf = kGasConstant * kTemperature / kFaraday;
  // Gate steady states (2004 paper, Appendix; IKs, Ito, ICaL as updated in 2006).
  const double m_inf = Sigmoid((-56.86 - v) / 9.03);
  const double hj_inf = Sigmoid((v + 71.55) / 7.43);
  terms[kMInf] = m_inf * m_inf;
  terms[kHJInf] = hj_inf * hj_inf;
  terms[kXr1Inf] = Sigmoid((-26.0 - v) / 7.0);
  terms[kXr2Inf] = Sigmoid((v + 88.0) / 24.0);
  terms[kXsInf] = Sigmoid((-5.0 - v) / 14.0);
  terms[kRInf] = Sigmoid((20.0 - v) / 6.0);
  // The s gate differs between the endocardium and the other variants.
  terms[kSInf] = Sigmoid((v + (p.variant == Variant::kEndo ? 28.0 : 20.0)) / 5.0);
  terms[kDInf] = Sigmoid((-8.0 - v) / 7.5);
  terms[kFInf] = Sigmoid((v + 20.0) / 7.0);
  terms[kF2Inf] = 0.67 * Sigmoid((v + 35.0) / 7.0) + 0.33;
  // ICaL = g d f f2 fCass · 4 (V − 15) F²/(RT) · (0.25 CaSS e^x − Cao)/(e^x − 1),
  // x = 2 (V − 15) F/(RT); with B(x) = x/(e^x − 1) and x e^x/(e^x − 1) = B(−x):
  // ICaL = g d f f2 fCass · 2F (0.25 CaSS B(−x) − Cao B(x)).
  const double x = 2.0 * (v - 15.0) / rtf;
  terms[kCaLCaSS] = 0.5 * p.g_cal * kFaraday * XOverExpm1(-x);
  terms[kCaLCao] = 2.0 * p.g_cal * kFaraday * p.cao * XOverExpm1(x);
  // INaCa.
  const double e_up = std::exp(kNaCaGamma * v / rtf);
  const double e_down = std::exp((kNaCaGamma - 1.0) * v / rtf);
  const double den =
      (kKmNai * kKmNai * kKmNai + p.nao * p.nao * p.nao) * (kKmCa + p.cao) * (1.0 + kKsat * e_down);
  terms[kNaCaNai] = p.k_naca * e_up * p.cao / den;
  terms[kNaCaCai] = p.k_naca * e_down * p.nao * p.nao * p.nao * kNaCaAlpha / den;
  // INaK and IpK.
  terms[kNaK] = p.p_nak * p.ko / (p.ko + kKmK) /
                (1.0 + 0.1245 * std::exp(-0.1 * v / rtf) + 0.0353 * std::exp(-v / rtf));
  terms[kPK] = p.g_pk * Sigmoid((25.0 - v) / 5.98);
}

void TenTusscherPanfilov2006::CalcGateRates(double v, double* rates) const {
  // Indices follow the decay terms: rates[k] belongs to Term kMDecay + k.
  {
    const double alpha = Sigmoid((-60.0 - v) / 5.0);
    const double beta = 0.1 * Sigmoid((v + 35.0) / 5.0) + 0.1 * Sigmoid((v - 50.0) / 200.0);
    rates[kMDecay - kMDecay] = 1.0 / (alpha * beta);
  }
  {
    double alpha_h = 0.0, beta_h, alpha_j = 0.0, beta_j;
    if (v < -40.0) {
      alpha_h = 0.057 * std::exp(-(v + 80.0) / 6.8);
      beta_h = 2.7 * std::exp(0.079 * v) + 3.1e5 * std::exp(0.3485 * v);
      alpha_j = (-25428.0 * std::exp(0.2444 * v) - 6.948e-6 * std::exp(-0.04391 * v)) *
                (v + 37.78) / (1.0 + std::exp(0.311 * (v + 79.23)));
      beta_j = 0.02424 * std::exp(-0.01052 * v) / (1.0 + std::exp(-0.1378 * (v + 40.14)));
    } else {
      beta_h = 0.77 / (0.13 * (1.0 + std::exp(-(v + 10.66) / 11.1)));
      beta_j = 0.6 * std::exp(0.057 * v) / (1.0 + std::exp(-0.1 * (v + 32.0)));
    }
    rates[kHDecay - kMDecay] = alpha_h + beta_h;
    rates[kJDecay - kMDecay] = alpha_j + beta_j;
  }
  {
    const double alpha = 450.0 * Sigmoid((-45.0 - v) / 10.0);
    const double beta = 6.0 * Sigmoid((v + 30.0) / 11.5);
    rates[kXr1Decay - kMDecay] = 1.0 / (alpha * beta);
  }
  {
    const double alpha = 3.0 * Sigmoid((-60.0 - v) / 20.0);
    const double beta = 1.12 * Sigmoid((v - 60.0) / 20.0);
    rates[kXr2Decay - kMDecay] = 1.0 / (alpha * beta);
  }
  {
    const double alpha = 1400.0 / std::sqrt(1.0 + std::exp((5.0 - v) / 6.0));
    const double beta = Sigmoid((v - 35.0) / 15.0);
    rates[kXsDecay - kMDecay] = 1.0 / (alpha * beta + 80.0);  // + 80 ms in the 2006 model
  }
  rates[kRDecay - kMDecay] = 1.0 / (9.5 * std::exp(-(v + 40.0) * (v + 40.0) / 1800.0) + 0.8);
  if (params_.variant == Variant::kEndo) {
    rates[kSDecay - kMDecay] = 1.0 / (1000.0 * std::exp(-(v + 67.0) * (v + 67.0) / 1000.0) + 8.0);
  } else {
    rates[kSDecay - kMDecay] = 1.0 / (85.0 * std::exp(-(v + 45.0) * (v + 45.0) / 320.0) +
                                      5.0 * Sigmoid((v - 20.0) / 5.0) + 3.0);
  }
  {
    const double alpha = 1.4 * Sigmoid((-35.0 - v) / 13.0) + 0.25;
    const double beta = 1.4 * Sigmoid((v + 5.0) / 5.0);
    const double gamma = Sigmoid((50.0 - v) / 20.0);
    rates[kDDecay - kMDecay] = 1.0 / (alpha * beta + gamma);
  }
  rates[kFDecay - kMDecay] =
      1.0 / (1102.5 * std::exp(-(v + 27.0) * (v + 27.0) / 225.0) +
             200.0 * Sigmoid((13.0 - v) / 10.0) + 180.0 * Sigmoid((v + 30.0) / 10.0) + 20.0);
  rates[kF2Decay - kMDecay] =
      1.0 / (562.0 * std::exp(-(v + 27.0) * (v + 27.0) / 240.0) +
             31.0 * Sigmoid((25.0 - v) / 10.0) + 80.0 * Sigmoid((v + 30.0) / 10.0));
}

double TenTusscherPanfilov2006::CalcK1Rectification(double dk) {
  const double alpha = 0.1 / (1.0 + std::exp(0.06 * (dk - 200.0)));
  const double beta = (3.0 * std::exp(0.0002 * (dk + 100.0)) + std::exp(0.1 * (dk - 10.0))) /
                      (1.0 + std::exp(-0.5 * dk));
  return alpha / (alpha + beta);
}

void TenTusscherPanfilov2006::Prepare(double dt) const {
  GIPSI_CHECK(dt > 0 && std::isfinite(dt), "dt = {}", dt);
  (void)DecayTable(dt);
}

const LookupTable* TenTusscherPanfilov2006::DecayTable(double dt) const {
  if (!voltage_table_) return nullptr;
  const DecayTableEntry* last = last_decay_.load(std::memory_order_acquire);
  if (last && last->dt == dt) return &last->table;
  std::lock_guard<std::mutex> lock(decay_mutex_);
  for (const auto& entry : decay_tables_) {
    if (entry->dt == dt) {
      last_decay_.store(entry.get(), std::memory_order_release);
      return &entry->table;
    }
  }
  if (decay_tables_.size() >= kMaxDecayTables) return nullptr;
  decay_tables_.push_back(std::make_unique<const DecayTableEntry>(
      DecayTableEntry{dt, LookupTable(kTableVMin, kTableVMax, params_.table_step, kNumVoltageGates,
                                      [this, dt](double v, double* row) {
                                        CalcGateRates(v, row);
                                        for (int k = 0; k < kNumVoltageGates; ++k)
                                          row[k] = std::exp(-dt * row[k]);
                                      })}));
  last_decay_.store(decay_tables_.back().get(), std::memory_order_release);
  return &decay_tables_.back()->table;
}

void TenTusscherPanfilov2006::FillTerms(const ConstCellStateView& states, std::size_t first,
                                        std::size_t count, double dt, const LookupTable* decay,
                                        double* terms) const {
  const TenTusscherPanfilov2006Constants& c = *constants_;
  const double* __restrict voltage = states.var(kV) + first;
  const double* __restrict ki = states.var(kKi) + first;
  double* __restrict ek = terms + kEK * kChunk;
  // EK (vectorised), then per node the table lookups (gathers, scalar).
#pragma omp simd
  for (std::size_t j = 0; j < count; ++j) ek[j] = c.rtf * (c.log_ko - simd::FastLog(ki[j]));
  double row[kNumTerms];
  for (std::size_t j = 0; j < count; ++j) {
    const double v = voltage[j];
    if (voltage_table_) {
      const LookupTable::Position at = voltage_table_->Locate(v);
      for (int t = 0; t < kNumVoltageTerms; ++t) row[t] = voltage_table_->Interpolate(at, t);
      if (dt > 0) {
        if (decay) {
          for (int k = 0; k < kNumVoltageGates; ++k) row[kMDecay + k] = decay->Interpolate(at, k);
        } else {  // more distinct dt than the cache holds
          CalcGateRates(v, row + kMDecay);
          for (int k = 0; k < kNumVoltageGates; ++k)
            row[kMDecay + k] = std::exp(-dt * row[kMDecay + k]);
        }
      }
      row[kK1Rect] = k1_table_->Interpolate(k1_table_->Locate(v - ek[j]), 0);
    } else {
      CalcVoltageTerms(v, row);
      if (dt > 0) {
        CalcGateRates(v, row + kMDecay);
        for (int k = 0; k < kNumVoltageGates; ++k)
          row[kMDecay + k] = std::exp(-dt * row[kMDecay + k]);
      }
      row[kK1Rect] = CalcK1Rectification(v - ek[j]);
    }
    const int last = dt > 0 ? kEK : kMDecay;
    for (int t = 0; t < last; ++t) terms[static_cast<std::size_t>(t) * kChunk + j] = row[t];
    terms[static_cast<std::size_t>(kK1Rect) * kChunk + j] = row[kK1Rect];
  }
}

namespace {

/// The twelve currents of one node [µA/µF].
struct Currents {
  double ina, ik1, ito, ikr, iks, ical, inak, inaca, ipca, ipk, ibca, ibna;
  [[nodiscard]] double Total() const {
    return ina + ik1 + ito + ikr + iks + ical + inak + inaca + ipca + ipk + ibca + ibna;
  }
};

/// The gates a node's currents depend on.
struct Gates {
  double m, h, j, xr1, xr2, xs, r, s, d, f, f2, fcass;
};

/// The currents of one node from its state and its terms `t` (stride kChunk).
/// Branch-free, so that the loops over nodes vectorise.
[[gnu::always_inline]] inline Currents CalcCurrents(const TenTusscherPanfilov2006Constants& c,
                                                    double v, double cai, double cass, double nai,
                                                    double ki, const Gates& g, const double* t) {
  const double e_na = c.rtf * (c.log_nao - simd::FastLog(nai));
  const double e_k = t[kEK * kChunk];
  const double e_ks = c.rtf * (c.log_eks_num - simd::FastLog(ki + kPKNa * nai));
  const double e_ca = 0.5 * c.rtf * (c.log_cao - simd::FastLog(cai));
  const double dk = v - e_k;
  const double x_k1 = t[kK1Rect * kChunk];
  Currents out;
  out.ina = c.g_na * g.m * g.m * g.m * g.h * g.j * (v - e_na);
  out.ik1 = c.g_k1 * x_k1 * dk;
  out.ito = c.g_to * g.r * g.s * dk;
  out.ikr = c.g_kr * g.xr1 * g.xr2 * dk;
  out.iks = c.g_ks * g.xs * g.xs * (v - e_ks);
  out.ical = g.d * g.f * g.f2 * g.fcass * (t[kCaLCaSS * kChunk] * cass - t[kCaLCao * kChunk]);
  out.inak = t[kNaK * kChunk] * nai / (nai + kKmNa);
  out.inaca = t[kNaCaNai * kChunk] * nai * nai * nai - t[kNaCaCai * kChunk] * cai;
  out.ipca = c.g_pca * cai / (cai + kKpCa);
  out.ipk = t[kPK * kChunk] * dk;
  out.ibca = c.g_bca * (v - e_ca);
  out.ibna = c.g_bna * (v - e_na);
  return out;
}

/// Rush–Larsen: x∞ + (x − x∞) e^(−dt/τ), given the decay factor e^(−dt/τ).
[[gnu::always_inline]] inline double RushLarsen(double x, double inf, double decay) {
  return inf + (x - inf) * decay;
}

}  // namespace

template <bool kStimulus>
void TenTusscherPanfilov2006::StepChunk(const CellStateView& states, std::size_t first,
                                        std::size_t count, double dt, const double* i_stim,
                                        const double* terms) const {
  const TenTusscherPanfilov2006Constants c = *constants_;
  const simd::ExpRange range = simd::ExpRange::Load();
  const double minus_dt = -dt;
  double* __restrict pv = states.var(kV) + first;
  double* __restrict pcai = states.var(kCai) + first;
  double* __restrict pcasr = states.var(kCaSR) + first;
  double* __restrict pcass = states.var(kCaSS) + first;
  double* __restrict pnai = states.var(kNai) + first;
  double* __restrict pki = states.var(kKi) + first;
  double* __restrict pm = states.var(kM) + first;
  double* __restrict ph = states.var(kH) + first;
  double* __restrict pj = states.var(kJ) + first;
  double* __restrict pxr1 = states.var(kXr1) + first;
  double* __restrict pxr2 = states.var(kXr2) + first;
  double* __restrict pxs = states.var(kXs) + first;
  double* __restrict pr = states.var(kR) + first;
  double* __restrict ps = states.var(kS) + first;
  double* __restrict pd = states.var(kD) + first;
  double* __restrict pf = states.var(kF) + first;
  double* __restrict pf2 = states.var(kF2) + first;
  double* __restrict pfcass = states.var(kFCass) + first;
  double* __restrict prp = states.var(kRPrime) + first;
  const double* __restrict stim = kStimulus ? i_stim + first : nullptr;
#pragma omp simd
  for (std::size_t i = 0; i < count; ++i) {
    const double* t = terms + i;
    const double v = pv[i], cai = pcai[i], casr = pcasr[i], cass = pcass[i], nai = pnai[i],
                 ki = pki[i];
    const Gates g{pm[i], ph[i], pj[i], pxr1[i], pxr2[i], pxs[i],
                  pr[i], ps[i], pd[i], pf[i],   pf2[i],  pfcass[i]};
    const double rp = prp[i];
    const Currents cur = CalcCurrents(c, v, cai, cass, nai, ki, g, t);
    const double i_applied = kStimulus ? stim[i] : 0.0;

    // Calcium handling (2006 paper: subspace, RyR four-state model reduced to R_prime).
    const double casr2 = casr * casr;
    const double kcasr = kMaxSR - (kMaxSR - kMinSR) * casr2 / (casr2 + kEC * kEC);
    const double k1 = kK1Prime / kcasr;
    const double k2 = kK2Prime * kcasr;
    const double cass2 = cass * cass;
    const double open = k1 * cass2 * rp / (kK3 + k1 * cass2);
    const double j_rel = kVrel * open * (casr - cass);
    const double j_leak = kVleak * (casr - cai);
    const double j_up = kVmaxUp * cai * cai / (cai * cai + kKup * kKup);
    const double j_xfer = kVxfer * (cass - cai);
    const double buf_c = 1.0 / (1.0 + kBufC * kKBufC / ((cai + kKBufC) * (cai + kKBufC)));
    const double buf_sr = 1.0 / (1.0 + kBufSR * kKBufSR / ((casr + kKBufSR) * (casr + kKBufSR)));
    const double buf_ss = 1.0 / (1.0 + kBufSS * kKBufSS / ((cass + kKBufSS) * (cass + kKBufSS)));
    const double dcai = buf_c * ((j_leak - j_up) * c.vsr_vc + j_xfer -
                                 (cur.ibca + cur.ipca - 2.0 * cur.inaca) * c.cm_2vc_f);
    const double dcass = buf_ss * (-cur.ical * c.cm_2vss_f + j_rel * c.vsr_vss - j_xfer * c.vc_vss);
    const double dcasr = buf_sr * (j_up - j_rel - j_leak);
    const double dnai = -(cur.ina + cur.ibna + 3.0 * cur.inak + 3.0 * cur.inaca) * c.cm_vc_f;
    const double dki =
        -(cur.ik1 + cur.ito + cur.ikr + cur.iks + cur.ipk - 2.0 * cur.inak - i_applied) * c.cm_vc_f;
    const double drp = -k2 * cass * rp + kK4 * (1.0 - rp);

    // fCass gate (depends on CaSS, not V).
    const double q = 1.0 / (1.0 + 400.0 * cass2);  // 1/(1 + (CaSS/0.05)²)
    const double fcass_inf = 0.6 * q + 0.4;
    const double fcass_tau = 80.0 * q + 2.0;

    // Forward Euler.
    pv[i] = v + dt * (i_applied - cur.Total());
    pcai[i] = cai + dt * dcai;
    pcass[i] = cass + dt * dcass;
    pcasr[i] = casr + dt * dcasr;
    pnai[i] = nai + dt * dnai;
    pki[i] = ki + dt * dki;
    prp[i] = rp + dt * drp;
    // Rush–Larsen.
    pm[i] = RushLarsen(g.m, t[kMInf * kChunk], t[kMDecay * kChunk]);
    ph[i] = RushLarsen(g.h, t[kHJInf * kChunk], t[kHDecay * kChunk]);
    pj[i] = RushLarsen(g.j, t[kHJInf * kChunk], t[kJDecay * kChunk]);
    pxr1[i] = RushLarsen(g.xr1, t[kXr1Inf * kChunk], t[kXr1Decay * kChunk]);
    pxr2[i] = RushLarsen(g.xr2, t[kXr2Inf * kChunk], t[kXr2Decay * kChunk]);
    pxs[i] = RushLarsen(g.xs, t[kXsInf * kChunk], t[kXsDecay * kChunk]);
    pr[i] = RushLarsen(g.r, t[kRInf * kChunk], t[kRDecay * kChunk]);
    ps[i] = RushLarsen(g.s, t[kSInf * kChunk], t[kSDecay * kChunk]);
    pd[i] = RushLarsen(g.d, t[kDInf * kChunk], t[kDDecay * kChunk]);
    pf[i] = RushLarsen(g.f, t[kFInf * kChunk], t[kFDecay * kChunk]);
    pf2[i] = RushLarsen(g.f2, t[kF2Inf * kChunk], t[kF2Decay * kChunk]);
    pfcass[i] = RushLarsen(g.fcass, fcass_inf, simd::FastExp(minus_dt / fcass_tau, range));
  }
}

void TenTusscherPanfilov2006::DoStep(const CellStateView& states, std::size_t begin,
                                     std::size_t end, double dt, const double* i_stim) const {
  alignas(64) double terms[kNumTerms * kChunk];
  const LookupTable* decay = DecayTable(dt);
  for (std::size_t first = begin; first < end; first += kChunk) {
    const std::size_t count = std::min(kChunk, end - first);
    FillTerms(states, first, count, dt, decay, terms);
    if (i_stim)
      StepChunk<true>(states, first, count, dt, i_stim, terms);
    else
      StepChunk<false>(states, first, count, dt, nullptr, terms);
  }
}

void TenTusscherPanfilov2006::DoCalcIonicCurrent(const ConstCellStateView& states,
                                                 std::size_t begin, std::size_t end,
                                                 double* i_ion) const {
  alignas(64) double terms[kNumTerms * kChunk];
  const TenTusscherPanfilov2006Constants c = *constants_;
  for (std::size_t first = begin; first < end; first += kChunk) {
    const std::size_t count = std::min(kChunk, end - first);
    FillTerms(states, first, count, 0.0, nullptr, terms);
    const double* __restrict pv = states.var(kV) + first;
    const double* __restrict pcai = states.var(kCai) + first;
    const double* __restrict pcass = states.var(kCaSS) + first;
    const double* __restrict pnai = states.var(kNai) + first;
    const double* __restrict pki = states.var(kKi) + first;
    const double* __restrict pm = states.var(kM) + first;
    const double* __restrict ph = states.var(kH) + first;
    const double* __restrict pj = states.var(kJ) + first;
    const double* __restrict pxr1 = states.var(kXr1) + first;
    const double* __restrict pxr2 = states.var(kXr2) + first;
    const double* __restrict pxs = states.var(kXs) + first;
    const double* __restrict pr = states.var(kR) + first;
    const double* __restrict ps = states.var(kS) + first;
    const double* __restrict pd = states.var(kD) + first;
    const double* __restrict pf = states.var(kF) + first;
    const double* __restrict pf2 = states.var(kF2) + first;
    const double* __restrict pfcass = states.var(kFCass) + first;
    double* __restrict out = i_ion + first;
#pragma omp simd
    for (std::size_t i = 0; i < count; ++i) {
      const double* t = terms + i;
      const Gates g{pm[i], ph[i], pj[i], pxr1[i], pxr2[i], pxs[i],
                    pr[i], ps[i], pd[i], pf[i],   pf2[i],  pfcass[i]};
      out[i] = CalcCurrents(c, pv[i], pcai[i], pcass[i], pnai[i], pki[i], g, t).Total();
    }
  }
}

}  // namespace gipsi
