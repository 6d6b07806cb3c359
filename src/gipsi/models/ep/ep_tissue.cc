/// @file
/// Operator splitting, stimuli, clamps, activation maps and fields of monodomain objects.

#include "gipsi/models/ep/ep_tissue.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "gipsi/base/error.h"
#include "gipsi/base/state_binding.h"
#include "gipsi/numerics/adaptive_parallel.h"

namespace gipsi {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// Cells stepped per task: a multiple of every SIMD width, large enough to amortise the call.
constexpr std::size_t kReactionChunk = 1024;
// Below this many nodes the reaction and tracking loops stay on the calling thread.
constexpr Index kMinParallelNodes = 4096;
// Share of an adaptive loop's timed calls that ran on the team [%] (0 before any).
double TeamShare(const AdaptiveParallel& loop) {
  const auto all = loop.parallel_calls() + loop.serial_calls();
  return all > 0 ? 100.0 * static_cast<double>(loop.parallel_calls()) / static_cast<double>(all)
                 : 0.0;
}

// |V| beyond this is no cardiac potential: the explicit reaction step has blown up.
constexpr double kVoltageBound = 1000.0;  // mV

}  // namespace

double PulseTrain::ActiveTime(double t0, double t1) const {
  if (t1 <= t0) return 0;
  const int last_pulse = period > 0 ? count - 1 : 0;
  int first = 0;
  int last = last_pulse;
  if (period > 0) {
    first = std::max(0, static_cast<int>(std::floor((t0 - start - duration) / period)));
    last = std::min(last_pulse, static_cast<int>(std::floor((t1 - start) / period)));
  }
  double active = 0;
  for (int k = first; k <= last; ++k) {
    const double on = start + k * period;
    active += std::max(0.0, std::min(t1, on + duration) - std::max(t0, on));
  }
  return active;
}

bool PulseTrain::ActiveAt(double t) const {
  if (t < start) return false;
  const int k = period > 0 ? static_cast<int>(std::floor((t - start) / period)) : 0;
  if (k >= (period > 0 ? count : 1)) return false;
  return t - (start + k * period) < duration;
}

// σ [S/m] / (χ [1/m] · Cm [F/m²]) is in m²/s; 1 m²/s = 10⁶ mm² / 10³ ms = 10³ mm²/ms.
double EpTissueParams::diffusivity_longitudinal() const {
  return 1e3 * sigma_longitudinal / (surface_to_volume * capacitance);
}
double EpTissueParams::diffusivity_transverse() const {
  return 1e3 * sigma_transverse / (surface_to_volume * capacitance);
}

EpTissue::EpTissue(std::string name, EpTissueParams params)
    : SimObject(std::move(name)), params_(std::move(params)) {
  const CellModel& model = *params_.cell;
  for (int k = 0; k < model.num_states(); ++k) {
    const CellStateInfo& s = model.states()[static_cast<std::size_t>(k)];
    const bool is_v = k == model.v_index();
    state_fields_.push_back(DeclareField(
        {is_v ? "V" : "cell_" + s.name, FieldLocation::kNode, 1, s.unit, FieldAccess::kReadWrite,
         is_v ? "transmembrane voltage"
              : fmt::format("cell-model state '{}' of {}", s.name, model.type_name())}));
  }
  f_activation_ =
      DeclareField({"activation_time", FieldLocation::kNode, 1, "ms", FieldAccess::kRead,
                    "first time V rose through the activation threshold (-1: never)", -1.0});
  f_last_activation_ =
      DeclareField({"last_activation_time", FieldLocation::kNode, 1, "ms", FieldAccess::kRead,
                    "latest activation time (-1: never)", -1.0});
  f_apd_ = DeclareField({"apd", FieldLocation::kNode, 1, "ms", FieldAccess::kRead,
                         "last completed action potential duration (-1: none yet)", -1.0});
  f_activated_ = DeclareField({"activated_fraction", FieldLocation::kGlobal, 1, "1",
                               FieldAccess::kRead, "fraction of nodes activated at least once"});
  f_integral_ = DeclareField({"voltage_integral", FieldLocation::kGlobal, 1, "mV*m^3",
                              FieldAccess::kRead, "mass-weighted integral of V over the domain"});
  f_cg_ = DeclareField({"diffusion_iterations", FieldLocation::kGlobal, 1, "1", FieldAccess::kRead,
                        "linear-solver iterations of the last diffusion step"});
  BindState(state_);
}

void EpTissue::InitTissue(TissueSetup setup) {
  const CellModel& model = *params_.cell;
  const auto n = static_cast<std::size_t>(domain().num_nodes());
  state_.cells = CellStates(model, n);
  if (!params_.initial_state.empty())
    for (std::size_t i = 0; i < n; ++i) state_.cells.SetNode(i, params_.initial_state);
  i_stim_ = VecX::Zero(static_cast<Index>(n));
  for (const StimulusSpec& s : params_.stimuli) {
    stim_nodes_.push_back(SelectNodes(s.region, domain()));
    if (setup.require_region_nodes && stim_nodes_.back().empty())
      throw InputError(fmt::format("stimulus '{}' selects no node of the domain", s.name));
  }
  for (const ClampSpec& c : params_.clamps) {
    clamp_nodes_.push_back(SelectNodes(c.region, domain()));
    if (setup.require_region_nodes && clamp_nodes_.back().empty())
      throw InputError(fmt::format("clamp '{}' selects no node of the domain", c.name));
  }
  const Index count = static_cast<Index>(n);
  v_prev_ = voltage();
  state_.activation_time = VecX::Constant(count, -1);
  state_.last_activation = VecX::Constant(count, -1);
  state_.apd = VecX::Constant(count, -1);
  state_.v_min = v_prev_;
  state_.v_peak = v_prev_;
  state_.depolarised.assign(n, 0);
  if (setup.serial_solver) solver_ = MakeLinearSolver(params_.linear);
  // Tables for the reaction sub-step now, so the first step does not build them (with no
  // reaction dt the sub-step is the object's dt, known at the first step).
  if (params_.reaction_dt > 0) model.Prepare(1e3 * params_.reaction_dt);
}

void EpTissue::SetDiffusionOperator(SparseMatrix stiffness, VecX lumped_mass,
                                    SparseMatrix consistent_mass) {
  stiffness_ = std::move(stiffness);
  stiffness_.makeCompressed();
  lumped_mass_ = std::move(lumped_mass);
  consistent_mass_ = std::move(consistent_mass);
  consistent_mass_.makeCompressed();
  system_dt_ = -1;  // reassemble at the next step
}

Eigen::Map<const VecX> EpTissue::voltage() const {
  return {state_.cells.var(params_.cell->v_index()), static_cast<Index>(state_.cells.num_nodes())};
}

double EpTissue::VoltageIntegral() const { return lumped_mass_.dot(voltage()); }

Vec3 EpTissue::NodePositionMm(Index node) const { return 1e3 * domain().nodes.col(node); }

StepStatus EpTissue::DoStep(double t, double dt) {
  const double t_ms = 1e3 * t;
  const double dt_ms = 1e3 * dt;
  failure_detail_.clear();
  v_prev_ = voltage();
  if (params_.splitting == SplittingScheme::kStrang) {
    ReactionSteps(t_ms, 0.5 * dt_ms);
    if (StepStatus s = Diffuse(dt_ms); !s.ok()) return s;
    ReactionSteps(t_ms + 0.5 * dt_ms, 0.5 * dt_ms);
  } else {
    ReactionSteps(t_ms, dt_ms);
    if (StepStatus s = Diffuse(dt_ms); !s.ok()) return s;
    ApplyClamps(t_ms + dt_ms);
  }
  if (StepStatus s = CheckVoltage(); !s.ok()) return s;
  TrackActivation(t_ms, dt_ms);
  ++profile_.steps;
  return StepStatus::Ok();
}

void EpTissue::ReactionSteps(double t0_ms, double length_ms) {
  const auto start = Clock::now();
  const double max_h = params_.reaction_dt > 0 ? 1e3 * params_.reaction_dt : length_ms;
  const int substeps = std::max(1, static_cast<int>(std::ceil(length_ms / max_h - 1e-9)));
  const double h = length_ms / substeps;
  const CellModel& model = *params_.cell;
  model.Prepare(h);
  const CellStateView view = state_.cells.view();
  const std::size_t n = view.num_nodes;
  const auto chunks = static_cast<std::ptrdiff_t>((n + kReactionChunk - 1) / kReactionChunk);
  for (int k = 0; k < substeps; ++k) {
    const double ta = t0_ms + k * h;
    const bool stimulated = FillStimulus(ta, ta + h);
    const std::span<const double> stim =
        stimulated ? std::span<const double>(i_stim_.data(), n) : std::span<const double>();
    const bool parallel = reaction_parallel_.Begin(static_cast<Index>(n) >= kMinParallelNodes &&
                                                   MaxTeamThreads() > 1);
    ForRange(std::ptrdiff_t{0}, chunks, parallel, [&](std::ptrdiff_t c) {
      const auto begin = static_cast<std::size_t>(c) * kReactionChunk;
      model.Step(view, begin, std::min(n, begin + kReactionChunk), h, stim);
    });
    reaction_parallel_.End();
    ApplyClamps(ta + h);
  }
  profile_.reaction += Seconds(start);
}

bool EpTissue::FillStimulus(double t0, double t1) {
  for (int node : stimulated_) i_stim_[node] = 0;
  stimulated_.clear();
  for (std::size_t s = 0; s < params_.stimuli.size(); ++s) {
    const StimulusSpec& spec = params_.stimuli[s];
    const double active = spec.pulses.ActiveTime(t0, t1);
    if (active <= 0) continue;
    // The current is scaled by the active fraction of the sub-step, so the injected charge is
    // exact whether or not the pulse edges fall on step boundaries.
    const double current = spec.amplitude * active / (t1 - t0);
    for (int node : stim_nodes_[s]) {
      i_stim_[node] += current;
      stimulated_.push_back(node);
    }
  }
  return !stimulated_.empty();
}

void EpTissue::ApplyClamps(double t) {
  double* v = v_data();
  for (std::size_t c = 0; c < params_.clamps.size(); ++c)
    if (params_.clamps[c].pulses.ActiveAt(t))
      for (int node : clamp_nodes_[c]) v[node] = params_.clamps[c].voltage;
}

StepStatus EpTissue::Diffuse(double dt_ms) {
  const auto start = Clock::now();
  int iterations = 0;
  const StepStatus status = SolveDiffusion(dt_ms, v_data(), iterations, failure_detail_);
  state_.last_iterations = iterations;
  profile_.cg_iterations += iterations;
  profile_.diffusion += Seconds(start);
  return status;
}

StepStatus EpTissue::SolveDiffusion(double dt_ms, double* v_ptr, int& iterations,
                                    std::string& detail) {
  const double theta = params_.theta;
  if (dt_ms != system_dt_) {
    system_ = theta * dt_ms * stiffness_;
    if (params_.lumped_mass) {
      for (Index i = 0; i < system_.rows(); ++i) system_.coeffRef(i, i) += lumped_mass_[i];
    } else {
      system_ += consistent_mass_;
    }
    system_.makeCompressed();
    solver_->AnalyzePattern(system_);
    if (!solver_->Factorize(system_))
      return StepStatus::Failed("the diffusion matrix M + theta dt K is not positive definite");
    system_dt_ = dt_ms;
  }
  Eigen::Map<VecX> v(v_ptr, num_nodes());
  if (params_.lumped_mass) {
    rhs_ = lumped_mass_.cwiseProduct(v);
  } else {
    solution_ = v;
    rhs_.resize(v.size());
    SymmetricSpMV(consistent_mass_, solution_, rhs_);
  }
  if (theta < 1) {
    solution_ = v;
    work_.resize(v.size());
    SymmetricSpMV(stiffness_, solution_, work_);
    rhs_ -= (1 - theta) * dt_ms * work_;
  }
  solution_ = v;  // warm start
  const LinearSolveStats stats = solver_->Solve(rhs_, solution_);
  iterations = stats.iterations;
  if (!stats.converged) {
    detail = fmt::format("{} reached a relative residual of {:.3g} (tolerance {:.3g})",
                         solver_->name(), stats.relative_residual, params_.linear.tolerance);
    return StepStatus::Failed("the diffusion solve did not converge", -1, stats.relative_residual);
  }
  v = solution_;
  return StepStatus::Ok();
}

StepStatus EpTissue::CheckVoltage() {
  const double* v = v_data();
  for (Index i = 0; i < num_nodes(); ++i) {
    if (std::isfinite(v[i]) && std::abs(v[i]) <= kVoltageBound) continue;
    const Vec3 x = NodePositionMm(i);
    failure_detail_ = fmt::format(
        "node {} at ({:.4g}, {:.4g}, {:.4g}) mm has V = {} mV; the reaction step is probably "
        "too long for the cell model (try a smaller reaction dt)",
        i, x.x(), x.y(), x.z(), v[i]);
    return StepStatus::Diverged("transmembrane voltage non-finite or beyond 1000 mV", i, v[i]);
  }
  return StepStatus::Ok();
}

void EpTissue::TrackActivation(double t0_ms, double dt_ms) {
  const auto start = Clock::now();
  const double* v = v_data();
  const double threshold = params_.activation_threshold;
  const double fraction = params_.apd_repolarisation;
  const Index n = num_nodes();
  const bool parallel = tracking_parallel_.Begin(n >= kMinParallelNodes && MaxTeamThreads() > 1);
  ForRange(Index{0}, n, parallel, [&](Index i) {
    const double v0 = v_prev_[i];
    const double v1 = v[i];
    if (!state_.depolarised[static_cast<std::size_t>(i)]) {
      if (v0 < threshold && v1 >= threshold) {
        // Linear interpolation of the crossing within the step.
        const double tc = t0_ms + dt_ms * (threshold - v0) / (v1 - v0);
        if (state_.activation_time[i] < 0) state_.activation_time[i] = tc;
        state_.last_activation[i] = tc;
        state_.v_peak[i] = v1;
        state_.depolarised[static_cast<std::size_t>(i)] = 1;
      } else {
        state_.v_min[i] = std::min(state_.v_min[i], v1);
      }
    } else {
      state_.v_peak[i] = std::max(state_.v_peak[i], v1);
      const double level = state_.v_peak[i] - fraction * (state_.v_peak[i] - state_.v_min[i]);
      if (v0 > level && v1 <= level) {
        const double tc = t0_ms + dt_ms * (v0 - level) / (v0 - v1);
        state_.apd[i] = tc - state_.last_activation[i];
        state_.depolarised[static_cast<std::size_t>(i)] = 0;
        state_.v_min[i] = v1;
      }
    }
  });
  tracking_parallel_.End();
  profile_.tracking += Seconds(start);
}

std::vector<SimObject::ProfileEntry> EpTissue::ProfileBreakdown() const {
  return {{"reaction (cell models)", profile_.reaction, "s"},
          {"diffusion (assembly and solves)", profile_.diffusion, "s"},
          {"activation and APD tracking", profile_.tracking, "s"},
          {"diffusion solver iterations", static_cast<double>(profile_.cg_iterations), ""},
          {"reaction loops on the team", TeamShare(reaction_parallel_), "%"},
          {"tracking loops on the team", TeamShare(tracking_parallel_), "%"}};
}

const double* EpTissue::DoFieldMemory(FieldId id) const {
  for (std::size_t k = 0; k < state_fields_.size(); ++k)
    if (id == state_fields_[k]) return state_.cells.var(static_cast<int>(k));
  if (id == f_activation_) return state_.activation_time.data();
  if (id == f_last_activation_) return state_.last_activation.data();
  if (id == f_apd_) return state_.apd.data();
  return nullptr;
}

void EpTissue::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  for (std::size_t k = 0; k < state_fields_.size(); ++k) {
    if (id != state_fields_[k]) continue;
    out = Eigen::Map<const VecX>(state_.cells.var(static_cast<int>(k)), num_nodes()).transpose();
    return;
  }
  if (id == f_activation_) {
    out = state_.activation_time.transpose();
  } else if (id == f_last_activation_) {
    out = state_.last_activation.transpose();
  } else if (id == f_apd_) {
    out = state_.apd.transpose();
  } else if (id == f_activated_) {
    const auto activated = (state_.activation_time.array() >= 0).count();
    out(0, 0) = num_nodes() > 0 ? static_cast<double>(activated) / num_nodes() : 0.0;
  } else if (id == f_integral_) {
    out(0, 0) = 1e-9 * VoltageIntegral();  // mV·mm³ → mV·m³
  } else if (id == f_cg_) {
    out(0, 0) = state_.last_iterations;
  }
}

void EpTissue::DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) {
  for (std::size_t k = 0; k < state_fields_.size(); ++k) {
    if (id != state_fields_[k]) continue;
    Eigen::Map<VecX>(state_.cells.var(static_cast<int>(k)), num_nodes()) = in.row(0).transpose();
    return;
  }
}

StateRows EpTissue::ReadStateRows(StateReader& in, const ItemCounts& counts) const {
  // What SaveObjectState writes: the bound EpState and no cache.
  EpState read = EpState::Sized(cell(), static_cast<std::size_t>(counts.nodes));
  BindStateValue(read)->Read(in, {});
  StateRows rows;
  rows.node_width = EpState::RowWidth(cell());
  rows.node = read.ToRows();
  StateWriter shared;
  shared.WriteInt(read.last_iterations);
  rows.shared = shared.TakeBytes();
  return rows;
}

void EpTissue::WriteStateRows(StateWriter& out, const StateRows& rows) const {
  EpState written = EpState::Sized(cell(), static_cast<std::size_t>(num_nodes()));
  StateReader shared(rows.shared, fmt::format("object '{}': the shared state", name()));
  if (rows.node_width != EpState::RowWidth(cell()) || rows.tet_width != 0 || rows.face_width != 0)
    shared.Fail(
        fmt::format("rows of {}/{}/{} values per node/tet/face, where a Monodomain of "
                    "this cell model has {}/0/0",
                    rows.node_width, rows.tet_width, rows.face_width, EpState::RowWidth(cell())));
  written.FromRows(rows.node);
  written.last_iterations = static_cast<int>(shared.ReadInt());
  BindStateValue(written)->Write(out);
}

}  // namespace gipsi
