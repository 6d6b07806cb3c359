#include "gipsi/models/circulation/circuit.h"

#include <cmath>
#include <numbers>

#include "gipsi/base/error.h"

namespace gipsi {

double FlowWaveform::Evaluate(double t, double field_value) const {
  switch (kind) {
    case Kind::kConstant:
      return mean;
    case Kind::kSine:
      return mean + amplitude * std::sin(2 * std::numbers::pi * t / period);
    case Kind::kHalfSine: {
      double tau = std::fmod(t, period);
      if (tau < 0) tau += period;
      return tau < duration ? amplitude * std::sin(std::numbers::pi * tau / duration) : 0.0;
    }
    case Kind::kField:
      return field_value;
  }
  return 0;
}

Circuit::Circuit(std::vector<CompartmentSpec> compartments, std::vector<ConnectionSpec> connections,
                 CircuitState& state)
    : compartments_(std::move(compartments)), connections_(std::move(connections)), s_(state) {
  const int nc = num_compartments();
  GIPSI_CHECK(nc >= 1, "a circuit needs a compartment");
  for (const auto& c : compartments_) {
    using K = CompartmentSpec::Kind;
    if (c.kind == K::kCompliance) GIPSI_CHECK(c.compliance > 0, "{}: compliance", c.name);
    if (c.kind == K::kChamber && c.drive == CompartmentSpec::Drive::kElastance)
      GIPSI_CHECK(c.e_max >= c.e_min && c.e_min > 0, "{}: elastances", c.name);
    if (c.kind == K::kChamber && c.drive == CompartmentSpec::Drive::kVolume)
      GIPSI_CHECK(c.compliance > 0, "{}: coupling compliance", c.name);
  }
  size_ = nc;
  for (int i = 0; i < num_connections(); ++i) {
    const auto& c = connections_[static_cast<std::size_t>(i)];
    GIPSI_CHECK(c.to >= 0 && c.to < nc, "{}: 'to' out of range", c.name);
    GIPSI_CHECK((c.kind == ConnectionSpec::Kind::kSource && c.from == -1) ||
                    (c.from >= 0 && c.from < nc && c.from != c.to),
                "{}: 'from' out of range", c.name);
    if (c.kind != ConnectionSpec::Kind::kSource)
      GIPSI_CHECK(c.resistance > 0 || c.inertance > 0, "{}: needs R or L", c.name);
    flow_state_.push_back(c.inertial() ? size_++ : -1);
    if (c.kind == ConnectionSpec::Kind::kValve) valves_.push_back(i);
  }
  s_.valves.assign(valves_.size(), ValveState::kClosed);
  s_.cavity_volume.assign(static_cast<std::size_t>(nc), 0.0);
  s_.cavity_rate.assign(static_cast<std::size_t>(nc), 0.0);
  s_.cavity_time.assign(static_cast<std::size_t>(nc), 0.0);
  for (int i = 0; i < nc; ++i)
    s_.cavity_volume[static_cast<std::size_t>(i)] =
        compartments_[static_cast<std::size_t>(i)].initial_cavity_volume;
  s_.chamber_pressure.assign(static_cast<std::size_t>(nc), 0.0);
  for (int i = 0; i < nc; ++i)
    s_.chamber_pressure[static_cast<std::size_t>(i)] =
        compartments_[static_cast<std::size_t>(i)].initial_pressure;
  s_.source_value.assign(connections_.size(), 0.0);
  s_.resistance.clear();
  for (const auto& c : connections_) s_.resistance.push_back(c.resistance);
  p_work_.setZero(nc);
  q_work_.setZero(num_connections());
}

int Circuit::ResistanceProblem() const {
  for (int c = 0; c < num_connections(); ++c) {
    if (connections_[static_cast<std::size_t>(c)].kind == ConnectionSpec::Kind::kSource) continue;
    const double r = s_.resistance[static_cast<std::size_t>(c)];
    const bool inertial = connections_[static_cast<std::size_t>(c)].inertance > 0;
    if (!std::isfinite(r) || r < 0 || (r == 0 && !inertial)) return c;
  }
  return -1;
}

VecX Circuit::InitialState() const {
  VecX x = VecX::Zero(size_);
  for (int i = 0; i < num_compartments(); ++i)
    x[i] = compartments_[static_cast<std::size_t>(i)].initial_volume;
  for (int c = 0; c < num_connections(); ++c)
    if (flow_state(c) >= 0)
      x[flow_state(c)] = connections_[static_cast<std::size_t>(c)].initial_flow;
  return x;
}

double Circuit::Elastance(int c, double t) const {
  const auto& s = compartments_[static_cast<std::size_t>(c)];
  if (s.kind != CompartmentSpec::Kind::kChamber || s.drive != CompartmentSpec::Drive::kElastance)
    return 0;
  return s.e_min + (s.e_max - s.e_min) * s.activation.Evaluate(t);
}

double Circuit::CavityVolume(int c, double t) const {
  const auto i = static_cast<std::size_t>(c);
  return s_.cavity_volume[i] + s_.cavity_rate[i] * (t - s_.cavity_time[i]);
}

void Circuit::SetCavityVolume(int c, double volume, double t_written) {
  const auto i = static_cast<std::size_t>(c);
  s_.cavity_volume[i] = volume;
  s_.cavity_time[i] = t_written;
}

void Circuit::SetCavityVolumeRate(int c, double rate, double t_written) {
  const auto i = static_cast<std::size_t>(c);
  // Keep V_cav continuous at the time of writing: re-anchor the volume there.
  s_.cavity_volume[i] = CavityVolume(c, t_written);
  s_.cavity_time[i] = t_written;
  s_.cavity_rate[i] = rate;
}

void Circuit::CalcPressures(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> p) const {
  using K = CompartmentSpec::Kind;
  for (int i = 0; i < num_compartments(); ++i) {
    const auto& s = compartments_[static_cast<std::size_t>(i)];
    switch (s.kind) {
      case K::kChamber:
        switch (s.drive) {
          case CompartmentSpec::Drive::kElastance:
            p[i] = Elastance(i, t) * (x[i] - s.unstressed_volume);
            break;
          case CompartmentSpec::Drive::kVolume:
            p[i] = (x[i] - CavityVolume(i, t)) / s.compliance;
            break;
          case CompartmentSpec::Drive::kPressure:
            p[i] = s_.chamber_pressure[static_cast<std::size_t>(i)];
            break;
        }
        break;
      case K::kCompliance:
        p[i] = (x[i] - s.unstressed_volume) / s.compliance;
        break;
      case K::kReservoir:
        p[i] = s.reservoir_pressure;
        break;
    }
  }
}

void Circuit::CalcFlows(double t, Eigen::Ref<const VecX> x, Eigen::Ref<const VecX> p,
                        Eigen::Ref<VecX> q) const {
  int valve = 0;
  for (int c = 0; c < num_connections(); ++c) {
    const auto& s = connections_[static_cast<std::size_t>(c)];
    bool open = true;
    if (s.kind == ConnectionSpec::Kind::kValve)
      open = s_.valves[static_cast<std::size_t>(valve++)] == ValveState::kOpen;
    if (s.kind == ConnectionSpec::Kind::kSource) {
      q[c] = s.source.Evaluate(t, s_.source_value[static_cast<std::size_t>(c)]);
    } else if (!open) {
      q[c] = 0;
    } else if (flow_state(c) >= 0) {
      q[c] = x[flow_state(c)];
    } else {
      q[c] = (p[s.from] - p[s.to]) / s_.resistance[static_cast<std::size_t>(c)];
    }
  }
}

void Circuit::CalcDerivative(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> xdot) const {
  CalcPressures(t, x, p_work_);
  CalcFlows(t, x, p_work_, q_work_);
  xdot.setZero();
  int valve = 0;
  for (int c = 0; c < num_connections(); ++c) {
    const auto& s = connections_[static_cast<std::size_t>(c)];
    const double q = q_work_[c];
    if (s.from >= 0) xdot[s.from] -= q;
    xdot[s.to] += q;
    bool open = true;
    if (s.kind == ConnectionSpec::Kind::kValve)
      open = s_.valves[static_cast<std::size_t>(valve++)] == ValveState::kOpen;
    if (flow_state(c) >= 0)
      xdot[flow_state(c)] =
          open
              ? (p_work_[s.from] - p_work_[s.to] - s_.resistance[static_cast<std::size_t>(c)] * q) /
                    s.inertance
              : 0.0;
  }
}

void Circuit::SwitchValve(int k, Eigen::Ref<VecX> x) {
  auto& state = s_.valves[static_cast<std::size_t>(k)];
  state = NextValveState(state);
  const int c = valves_[static_cast<std::size_t>(k)];
  if (state == ValveState::kClosed && flow_state(c) >= 0) x[flow_state(c)] = 0;
}

void Circuit::InitialiseValves(double t, Eigen::Ref<VecX> x) {
  CalcPressures(t, x, p_work_);
  for (std::size_t k = 0; k < valves_.size(); ++k) {
    const auto& s = connections_[static_cast<std::size_t>(valves_[k])];
    const Index fs = flow_state(valves_[k]);
    const bool open = p_work_[s.from] > p_work_[s.to] || (fs >= 0 && x[fs] > 0);
    s_.valves[k] = open ? ValveState::kOpen : ValveState::kClosed;
    if (!open && fs >= 0) x[fs] = 0;
  }
}

int Circuit::Guards::num_events() const { return static_cast<int>(circuit_->valves_.size()); }

void Circuit::Guards::Calc(double t, Eigen::Ref<const VecX> x, Eigen::Ref<VecX> g) const {
  const Circuit& c = *circuit_;
  c.CalcPressures(t, x, c.p_work_);
  for (std::size_t k = 0; k < c.valves_.size(); ++k) {
    const int conn = c.valves_[k];
    const auto& s = c.connections_[static_cast<std::size_t>(conn)];
    const Index fs = c.flow_state(conn);
    const double q = fs >= 0 ? x[fs] : 0.0;
    g[static_cast<Index>(k)] =
        ValveGuard(c.s_.valves[k], fs >= 0, c.p_work_[s.from] - c.p_work_[s.to], q);
  }
}

}  // namespace gipsi
