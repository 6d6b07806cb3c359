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
  // Objects split over the processes of a distributed run: split alike (collective when both
  // are split), or either holding only its part (whose items are this process's alone).
  const auto* ep_split = dynamic_cast<const PartitionedObject*>(&ep);
  auto* muscle_split = dynamic_cast<PartitionedObject*>(&muscle);
  const bool part_only = (ep_split != nullptr && !ep_split->holds_whole_domain()) ||
                         (muscle_split != nullptr && !muscle_split->holds_whole_domain());
  const bool alike = SplitAlike(ep, muscle);
  if (alike) {  // couple the parts, process by process
    split_ = ep_split;
    agree_on_ = ep_split;
    ep_ = &split_->local_part();
    muscle_ = &muscle_split->local_part();
    voltage_ = ep_->FindField(v.name);
    tension_field_ = muscle_->FindField(ta.name);
    Log().debug("{}: couples the parts of {} and {}, each process its own (split alike)", path(),
                ep.path(), muscle.path());
  }
  const Points src = ItemRestPositions(*ep_, FieldLocation::kNode);
  Points dst = ItemRestPositions(*muscle_, ta.location);
  // Items of differently split parts never coincide (and comparing them on one process would
  // decide differently on another).
  const bool coincide = (alike || !part_only) && src.cols() == dst.cols() &&
                        (src - dst).cwiseAbs().maxCoeff() <= 1e-12;
  if (!alike && !coincide && (ep_split != nullptr || muscle_split != nullptr)) {
    // Split differently (another mesh, another cut) or one end whole on every process: a split
    // muscle's part takes V at its own items; a split EP object's parts answer for them
    // (PartitionedObject::InterpolateAtPoints), a whole one interpolates in its own tets.
    if (muscle_split != nullptr) {
      agree_on_ = muscle_split;
      muscle_ = &muscle_split->local_part();
      tension_field_ = muscle_->FindField(ta.name);
      dst = ItemRestPositions(*muscle_, ta.location);
    }
    if (ep_split != nullptr) {
      interpolation_ = ep_split->InterpolateAtPoints(dst);
    } else {
      map_ = ep_->MapFromNodes(dst);
    }
    Log().debug("{}: interpolates V of {} at the items of {}, each process its own", path(),
                ep.path(), muscle.path());
  } else if (!coincide) {
    map_ = ep_->MapFromNodes(dst);
  }
  source_.resize(1, interpolation_ ? 0 : src.cols());
  mapped_.resize(1, dst.cols());
  tension_.resize(1, dst.cols());
  BindState(state_);
}

StepStatus ExcitationContraction::DoFire(double t) {
  if (interpolation_) {
    interpolation_->Interpolate(voltage_, mapped_, std::nullopt);
  } else {
    ep_->ReadField(voltage_, source_);
    if (split_ != nullptr) split_->ShareOwnedNodeValues(source_);
    if (map_) {
      map_->Apply(source_, mapped_);
    } else {
      mapped_ = source_;
    }
  }
  // Every process stops alike when coupling parts (each sees its own).
  if (const auto bad = FirstNonFinite(mapped_, tension_location_, agree_on_))
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
  // part's own interpolation, at its tets; between objects split any other way (another mesh),
  // or with one end whole, the EP object's parts answer for the muscle's items.
  registry.connector_part_use["ExcitationContraction"] = [](const JsonNode&) {
    return TypeRegistry::PartUse::kAnyParts;
  };
}

}  // namespace gipsi
