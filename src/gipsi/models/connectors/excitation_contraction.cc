/// @file
/// Excitation–contraction coupling (voltage → active tension).

#include "gipsi/models/connectors/excitation_contraction.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/units.h"
#include "gipsi/models/connectors/item_positions.h"

namespace gipsi {

ExcitationContraction::ExcitationContraction(std::string name, const SimObject& ep, FieldId voltage,
                                             SimObject& muscle, FieldId tension,
                                             const ExcitationContractionParams& params)
    : Connector(std::move(name)),
      ep_(&ep),
      voltage_(voltage),
      muscle_(&muscle),
      tension_field_(tension),
      params_(params) {
  const FieldInfo& v = ep.field_info(voltage);
  const FieldInfo& ta = muscle.field_info(tension);
  if (v.location != FieldLocation::kNode || v.components != 1 || !v.readable())
    throw InputError(
        fmt::format("'from' must be a readable scalar node field (the voltage); "
                    "'{}.{}' is not",
                    ep.path(), v.name));
  if ((ta.location != FieldLocation::kNode && ta.location != FieldLocation::kElement) ||
      ta.components != 1 || !ta.writable() || !ta.readable())
    throw InputError(
        fmt::format("'to' must be a readable and writable scalar node or element field (an "
                    "active tension the muscle keeps); '{}.{}' is not",
                    muscle.path(), ta.name));
  if (!(params.v_peak > params.v_rest)) throw InputError("v_peak must exceed v_rest");
  // v_rest and v_peak are in mV; the tension it writes in Pa.
  UseField("from", ep, v.name, FieldAccess::kRead, "mV", 1);
  UseField("to", muscle, ta.name, FieldAccess::kReadWrite, "Pa", 1);
  tension_location_ = ta.location;
  if (SplitAlike(ep, muscle)) {  // couple the parts, process by process
    split_ = dynamic_cast<const PartitionedObject*>(&ep);
    ep_ = &split_->local_part();
    muscle_ = &dynamic_cast<PartitionedObject&>(muscle).local_part();
    voltage_ = ep_->FindField(v.name);
    tension_field_ = muscle_->FindField(ta.name);
    Log().debug("{}: couples the parts of {} and {}, each process its own (split alike)", path(),
                ep.path(), muscle.path());
  }
  const Points src = ItemRestPositions(*ep_, FieldLocation::kNode);
  const Points dst = ItemRestPositions(*muscle_, ta.location);
  const bool coincide = src.cols() == dst.cols() && (src - dst).cwiseAbs().maxCoeff() <= 1e-12;
  if (!coincide) map_ = ep_->MapFromNodes(dst);
  source_.resize(1, src.cols());
  mapped_.resize(1, dst.cols());
  tension_.resize(1, dst.cols());
  BindState(state_);
}

StepStatus ExcitationContraction::DoFire(double t) {
  ep_->ReadField(voltage_, source_);
  if (split_ != nullptr) split_->ShareOwnedNodeValues(source_);
  if (map_) {
    map_->Apply(source_, mapped_);
  } else {
    mapped_ = source_;
  }
  // Every process stops alike when coupling parts (each sees its own).
  if (const auto bad = FirstNonFinite(mapped_, tension_location_, split_))
    return StepStatus::Diverged("non-finite voltage at item", bad->item, bad->value);
  const double dt = state_.fired ? t - state_.last_time : 0.0;
  muscle_->ReadField(tension_field_, tension_);  // the tension to relax from
  const ExcitationContractionParams& p = params_;
  for (Index i = 0; i < tension_.cols(); ++i) {
    const double u = std::clamp((mapped_(0, i) - p.v_rest) / (p.v_peak - p.v_rest), 0.0, 1.0);
    const double rate = u >= p.threshold ? p.rise_rate : p.decay_rate;
    const double target = p.gain * u;
    tension_(0, i) = target + (tension_(0, i) - target) * std::exp(-rate * dt);
  }
  muscle_->WriteField(tension_field_, tension_);
  state_.fired = true;
  state_.last_time = t;
  return StepStatus::Ok();
}

void RegisterExcitationContraction(TypeRegistry& registry) {
  registry.connectors.Register(
      "ExcitationContraction",
      [](const ConnectorBuildContext& ctx) -> std::unique_ptr<Connector> {
        ctx.CheckKeys(
            {"from", "to", "v_rest", "v_peak", "threshold", "gain", "rise_rate", "decay_rate"});
        const JsonNode& p = ctx.params;
        ExcitationContractionParams params;
        if (auto v = p.Find("v_rest")) params.v_rest = 1e3 * ReadQuantity(*v, "V");
        if (auto v = p.Find("v_peak")) params.v_peak = 1e3 * ReadQuantity(*v, "V");
        if (auto th = p.Find("threshold")) {
          params.threshold = th->AsNumber();
          if (!(params.threshold > 0 && params.threshold < 1))
            th->Expected("a fraction of the excitation in (0, 1)");
        }
        if (auto k = p.Find("gain")) params.gain = ReadPositiveQuantity(*k, "Pa", true);
        if (auto r = p.Find("rise_rate")) params.rise_rate = ReadPositiveQuantity(*r, "1/s");
        if (auto r = p.Find("decay_rate")) params.decay_rate = ReadPositiveQuantity(*r, "1/s");
        auto [ep, voltage] = ctx.ObjectField("from");
        auto [muscle, tension] = ctx.ObjectField("to");
        try {
          return std::make_unique<ExcitationContraction>(ctx.name, *ep, voltage, *muscle, tension,
                                                         params);
        } catch (const InputError& e) {
          p.Fail(e.what());
        }
      },
      "volume coupling: transmembrane voltage -> active tension (first-order twitch model)");
  // Between objects split alike it couples their parts, at the muscle's nodes or, through the
  // part's own interpolation, at its tets.
  registry.connector_part_use["ExcitationContraction"] = [](const JsonNode&) {
    return TypeRegistry::PartUse::kPartToPart;
  };
}

}  // namespace gipsi
