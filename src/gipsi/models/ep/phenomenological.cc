#include "gipsi/models/ep/phenomenological.h"

#include <cmath>

#include "gipsi/models/ep/cell_params.h"
#include "gipsi/models/ep/simd_math.h"

namespace gipsi {

// The kernels are plain loops over raw pointers; `#pragma omp simd` vectorises them (the
// results do not depend on vector width: only IEEE basic operations, evaluated in the same
// order in the vector body and the scalar remainder).

// ---------------------------------------------------------------------------------------------
// Aliev–Panfilov

namespace {

/// −du/dτ's excitation part: k u (u − a)(u − 1) + u v (so du/dτ = −AlievPanfilovF).
inline double AlievPanfilovF(const AlievPanfilovParams& p, double u, double v) {
  return p.k * u * (u - p.a) * (u - 1.0) + u * v;
}

}  // namespace

AlievPanfilov::AlievPanfilov(const AlievPanfilovParams& params)
    : CellModel({{"V", "mV"}, {"v", "1"}}, {params.scale.v_rest, 0.0}, 0), params_(params) {}

std::shared_ptr<const CellModel> AlievPanfilov::FromJson(const JsonNode& node) {
  node.CheckKeys({"model", "k", "a", "epsilon0", "mu1", "mu2", "time_scale", "v_rest", "v_peak"});
  AlievPanfilovParams p;
  p.k = node.Positive("k", p.k);
  p.a = ReadFraction(node, "a", p.a);
  p.epsilon0 = node.Positive("epsilon0", p.epsilon0);
  p.mu1 = node.NonNegative("mu1", p.mu1);
  p.mu2 = node.Positive("mu2", p.mu2);
  p.time_scale = node.Positive("time_scale", p.time_scale);
  p.scale = ReadVoltageScale(node, p.scale);
  return std::make_shared<AlievPanfilov>(p);
}

template <bool kStimulus>
void AlievPanfilov::StepRange(const CellStateView& states, std::size_t begin, std::size_t end,
                              double dt, const double* i_stim) const {
  const AlievPanfilovParams p = params_;
  const double v_rest = p.scale.v_rest;
  const double inv_amplitude = 1.0 / p.scale.amplitude();
  const double current_scale = p.scale.amplitude() / p.time_scale;  // I_ion per unit of F
  const double inv_time_scale = 1.0 / p.time_scale;
  double* __restrict voltage = states.var(0);
  double* __restrict recovery = states.var(1);
#pragma omp simd
  for (std::size_t i = begin; i < end; ++i) {
    const double u = (voltage[i] - v_rest) * inv_amplitude;
    const double v = recovery[i];
    const double i_ion = current_scale * AlievPanfilovF(p, u, v);
    const double epsilon = p.epsilon0 + p.mu1 * v / (u + p.mu2);
    const double dv = inv_time_scale * epsilon * (-v - p.k * u * (u - p.a - 1.0));
    double dvoltage = -i_ion;
    if constexpr (kStimulus) dvoltage += i_stim[i];
    voltage[i] += dt * dvoltage;
    recovery[i] = v + dt * dv;
  }
}

void AlievPanfilov::DoStep(const CellStateView& states, std::size_t begin, std::size_t end,
                           double dt, const double* i_stim) const {
  if (i_stim)
    StepRange<true>(states, begin, end, dt, i_stim);
  else
    StepRange<false>(states, begin, end, dt, nullptr);
}

void AlievPanfilov::DoCalcIonicCurrent(const ConstCellStateView& states, std::size_t begin,
                                       std::size_t end, double* i_ion) const {
  const AlievPanfilovParams p = params_;
  const double inv_amplitude = 1.0 / p.scale.amplitude();
  const double current_scale = p.scale.amplitude() / p.time_scale;
  const double* __restrict voltage = states.var(0);
  const double* __restrict recovery = states.var(1);
#pragma omp simd
  for (std::size_t i = begin; i < end; ++i) {
    const double u = (voltage[i] - p.scale.v_rest) * inv_amplitude;
    i_ion[i] = current_scale * AlievPanfilovF(p, u, recovery[i]);
  }
}

// ---------------------------------------------------------------------------------------------
// Mitchell–Schaeffer

MitchellSchaeffer::MitchellSchaeffer(const MitchellSchaefferParams& params)
    : CellModel({{"V", "mV"}, {"h", "1"}}, {params.scale.v_rest, 1.0}, 0), params_(params) {}

std::shared_ptr<const CellModel> MitchellSchaeffer::FromJson(const JsonNode& node) {
  node.CheckKeys(
      {"model", "tau_in", "tau_out", "tau_open", "tau_close", "v_gate", "v_rest", "v_peak"});
  MitchellSchaefferParams p;
  p.tau_in = node.Positive("tau_in", p.tau_in);
  p.tau_out = node.Positive("tau_out", p.tau_out);
  p.tau_open = node.Positive("tau_open", p.tau_open);
  p.tau_close = node.Positive("tau_close", p.tau_close);
  p.v_gate = ReadFraction(node, "v_gate", p.v_gate);
  p.scale = ReadVoltageScale(node, p.scale);
  return std::make_shared<MitchellSchaeffer>(p);
}

namespace {

/// −du/dt without stimulus: −(h u²(1 − u)/τ_in − u/τ_out).
inline double MitchellSchaefferF(double inv_tau_in, double inv_tau_out, double u, double h) {
  return -(h * u * u * (1.0 - u) * inv_tau_in - u * inv_tau_out);
}

}  // namespace

template <bool kStimulus>
void MitchellSchaeffer::StepRange(const CellStateView& states, std::size_t begin, std::size_t end,
                                  double dt, const double* i_stim) const {
  const double v_rest = params_.scale.v_rest;
  const double amplitude = params_.scale.amplitude();
  const double inv_amplitude = 1.0 / amplitude;
  const double inv_tau_in = 1.0 / params_.tau_in;
  const double inv_tau_out = 1.0 / params_.tau_out;
  const double v_gate = params_.v_gate;
  const double decay_open = std::exp(-dt / params_.tau_open);
  const double decay_close = std::exp(-dt / params_.tau_close);
  const double one = simd::Opaque(1.0), zero = simd::Opaque(0.0);  // keeps the loop vectorisable
  double* __restrict voltage = states.var(0);
  double* __restrict gate = states.var(1);
#pragma omp simd
  for (std::size_t i = begin; i < end; ++i) {
    const double u = (voltage[i] - v_rest) * inv_amplitude;
    const double h = gate[i];
    const double i_ion = amplitude * MitchellSchaefferF(inv_tau_in, inv_tau_out, u, h);
    const bool open = u < v_gate;
    const double h_inf = open ? one : zero;
    const double decay = open ? decay_open : decay_close;
    double dvoltage = -i_ion;
    if constexpr (kStimulus) dvoltage += i_stim[i];
    voltage[i] += dt * dvoltage;
    gate[i] = h_inf + (h - h_inf) * decay;
  }
}

void MitchellSchaeffer::DoStep(const CellStateView& states, std::size_t begin, std::size_t end,
                               double dt, const double* i_stim) const {
  if (i_stim)
    StepRange<true>(states, begin, end, dt, i_stim);
  else
    StepRange<false>(states, begin, end, dt, nullptr);
}

void MitchellSchaeffer::DoCalcIonicCurrent(const ConstCellStateView& states, std::size_t begin,
                                           std::size_t end, double* i_ion) const {
  const double v_rest = params_.scale.v_rest;
  const double amplitude = params_.scale.amplitude();
  const double inv_amplitude = 1.0 / amplitude;
  const double inv_tau_in = 1.0 / params_.tau_in;
  const double inv_tau_out = 1.0 / params_.tau_out;
  const double* __restrict voltage = states.var(0);
  const double* __restrict gate = states.var(1);
#pragma omp simd
  for (std::size_t i = begin; i < end; ++i) {
    const double u = (voltage[i] - v_rest) * inv_amplitude;
    i_ion[i] = amplitude * MitchellSchaefferF(inv_tau_in, inv_tau_out, u, gate[i]);
  }
}

// ---------------------------------------------------------------------------------------------
// FitzHugh–Nagumo and Nagumo

namespace {

std::vector<CellStateInfo> FitzHughNagumoStates(bool with_recovery) {
  if (with_recovery) return {{"V", "mV"}, {"w", "1"}};
  return {{"V", "mV"}};
}

std::vector<double> FitzHughNagumoRest(const FitzHughNagumoParams& p, bool with_recovery) {
  if (with_recovery) return {p.scale.v_rest, 0.0};
  return {p.scale.v_rest};
}

/// −du/dt without stimulus: −(c1 u (u − a)(1 − u) − c2 u w).
inline double FitzHughNagumoF(const FitzHughNagumoParams& p, double u, double w) {
  return -(p.c1 * u * (u - p.a) * (1.0 - u) - p.c2 * u * w);
}

}  // namespace

FitzHughNagumo::FitzHughNagumo(const FitzHughNagumoParams& params, bool with_recovery)
    : CellModel(FitzHughNagumoStates(with_recovery), FitzHughNagumoRest(params, with_recovery), 0),
      params_(params),
      with_recovery_(with_recovery) {}

std::shared_ptr<const CellModel> FitzHughNagumo::FromJson(const JsonNode& node,
                                                          bool with_recovery) {
  FitzHughNagumoParams p;
  if (with_recovery) {
    node.CheckKeys({"model", "a", "b", "c1", "c2", "c3", "v_rest", "v_peak"});
    p.b = node.Positive("b", p.b);
    p.c1 = node.Positive("c1", p.c1);
    p.c2 = node.NonNegative("c2", p.c2);
    p.c3 = node.NonNegative("c3", p.c3);
  } else {
    node.CheckKeys({"model", "k", "a", "v_rest", "v_peak"});
    p.c1 = node.Positive("k", p.c1);
    p.c2 = 0.0;
  }
  p.a = ReadFraction(node, "a", p.a);
  p.scale = ReadVoltageScale(node, p.scale);
  return std::make_shared<FitzHughNagumo>(p, with_recovery);
}

template <bool kStimulus, bool kRecovery>
void FitzHughNagumo::StepRange(const CellStateView& states, std::size_t begin, std::size_t end,
                               double dt, const double* i_stim) const {
  const FitzHughNagumoParams p = params_;
  const double v_rest = p.scale.v_rest;
  const double amplitude = p.scale.amplitude();
  const double inv_amplitude = 1.0 / amplitude;
  double* __restrict voltage = states.var(0);
  double* __restrict recovery = kRecovery ? states.var(1) : nullptr;
#pragma omp simd
  for (std::size_t i = begin; i < end; ++i) {
    const double u = (voltage[i] - v_rest) * inv_amplitude;
    const double w = kRecovery ? recovery[i] : 0.0;
    const double i_ion = amplitude * FitzHughNagumoF(p, u, w);
    double dvoltage = -i_ion;
    if constexpr (kStimulus) dvoltage += i_stim[i];
    voltage[i] += dt * dvoltage;
    if constexpr (kRecovery) recovery[i] = w + dt * (p.b * (u - p.c3 * w));
  }
}

void FitzHughNagumo::DoStep(const CellStateView& states, std::size_t begin, std::size_t end,
                            double dt, const double* i_stim) const {
  if (with_recovery_) {
    if (i_stim)
      StepRange<true, true>(states, begin, end, dt, i_stim);
    else
      StepRange<false, true>(states, begin, end, dt, nullptr);
  } else {
    if (i_stim)
      StepRange<true, false>(states, begin, end, dt, i_stim);
    else
      StepRange<false, false>(states, begin, end, dt, nullptr);
  }
}

void FitzHughNagumo::DoCalcIonicCurrent(const ConstCellStateView& states, std::size_t begin,
                                        std::size_t end, double* i_ion) const {
  const FitzHughNagumoParams p = params_;
  const double amplitude = p.scale.amplitude();
  const double inv_amplitude = 1.0 / amplitude;
  const double* __restrict voltage = states.var(0);
  const double* __restrict recovery = with_recovery_ ? states.var(1) : nullptr;
  if (with_recovery_) {
#pragma omp simd
    for (std::size_t i = begin; i < end; ++i) {
      const double u = (voltage[i] - p.scale.v_rest) * inv_amplitude;
      i_ion[i] = amplitude * FitzHughNagumoF(p, u, recovery[i]);
    }
  } else {
#pragma omp simd
    for (std::size_t i = begin; i < end; ++i) {
      const double u = (voltage[i] - p.scale.v_rest) * inv_amplitude;
      i_ion[i] = amplitude * FitzHughNagumoF(p, u, 0.0);
    }
  }
}

}  // namespace gipsi
