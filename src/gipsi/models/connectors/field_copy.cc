#include "gipsi/models/connectors/field_copy.h"

#include <cmath>
#include <optional>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/units.h"
#include "gipsi/models/connectors/item_positions.h"

namespace gipsi {

FieldCopy::FieldCopy(std::string name, SimObject& from, FieldId from_field, SimObject& to,
                     FieldId to_field, Mapping mapping, double scale,
                     const std::string& scale_units)
    : Connector(std::move(name)),
      from_(&from),
      from_field_(from_field),
      to_(&to),
      to_field_(to_field),
      mapping_(mapping),
      scale_(scale) {
  BindNoState();  // every Fire rewrites its buffers
  const FieldInfo& src = from.field_info(from_field);
  const FieldInfo& dst = to.field_info(to_field);
  auto fail = [&](const std::string& what) {
    throw InputError(fmt::format("connector '{}' ({}.{} → {}.{}): {}", this->path(), from.path(),
                                 src.name, to.path(), dst.name, what));
  };
  UseField("from", from, src.name, FieldAccess::kRead);
  UseField("to", to, dst.name, FieldAccess::kWrite, dst.units, dst.components);
  if (src.components != dst.components)
    fail(fmt::format("component counts differ ({} vs {})", src.components, dst.components));
  const Index n_src = from.FieldCount(from_field), n_dst = to.FieldCount(to_field);
  if ((src.location == FieldLocation::kGlobal) != (dst.location == FieldLocation::kGlobal))
    fail("a global field can only be copied to a global field");

  // The units: source × scale must give the target's, up to a factor we apply.
  const std::string carried =
      scale_units.empty() ? src.units : fmt::format("({})*({})", src.units, scale_units);
  try {
    scale_ = scale * UnitFactor(carried, dst.units);
  } catch (const std::invalid_argument&) {
    fail(scale_units.empty()
             ? fmt::format("the source is in [{}] and the target in [{}]; give \"scale\" with "
                           "the units that convert one into the other (e.g. \"1 {}/{}\")",
                           src.units, dst.units, dst.units,
                           src.units.find_first_of("/* .") == std::string::npos
                               ? src.units
                               : "(" + src.units + ")")
             : fmt::format("[{}] times the scale's [{}] does not give the target's [{}]", src.units,
                           scale_units, dst.units));
  }
  Points src_pos = ItemRestPositions(from, src.location);
  Points dst_pos = ItemRestPositions(to, dst.location);
  // Objects split over the processes of a distributed run: whether they are split alike
  // (collective when both are split), and whether either holds only its part, whose items are
  // then this process's alone.
  auto* from_split = dynamic_cast<const PartitionedObject*>(&from);
  auto* to_split = dynamic_cast<PartitionedObject*>(&to);
  const bool part_only = (from_split != nullptr && !from_split->holds_whole_domain()) ||
                         (to_split != nullptr && !to_split->holds_whole_domain());
  const bool alike = src.location != FieldLocation::kGlobal && SplitAlike(from, to);
  if (mapping_ == Mapping::kAuto) {
    // Items of differently split parts never pair one for one (and counting them on one
    // process would decide differently on another).
    const bool coincide = src.location == FieldLocation::kGlobal
                              ? n_src == n_dst
                              : (alike || !part_only) && n_src == n_dst &&
                                    (src_pos - dst_pos).cwiseAbs().maxCoeff() <= 1e-12;
    mapping_ = coincide                               ? Mapping::kDirect
               : src.location == FieldLocation::kNode ? Mapping::kBarycentric
                                                      : Mapping::kNearest;
  }
  if (mapping_ == Mapping::kDirect && part_only && !alike && src.location != FieldLocation::kGlobal)
    fail(
        "'direct' mapping between objects split differently over the processes (another mesh "
        "or another cut); use 'barycentric'");
  if (mapping_ == Mapping::kDirect && n_src != n_dst)
    fail(fmt::format("'direct' mapping needs equal item counts ({} vs {})", n_src, n_dst));
  if (mapping_ == Mapping::kBarycentric && src.location != FieldLocation::kNode)
    fail("'barycentric' mapping needs a node field as source");
  const bool onto_items =
      dst.location == FieldLocation::kNode || dst.location == FieldLocation::kElement;
  // A nearest item may be another process's: a split source's parts answer for each process's
  // target items (PartitionedObject::NearestAtPoints), except for a boundary field of a source
  // that holds its whole domain (whole on every process, as its nearest map below reads it).
  const bool boundary_source = src.location == FieldLocation::kBoundaryVertex ||
                               src.location == FieldLocation::kBoundaryFace;
  const bool nearest_parts =
      mapping_ == Mapping::kNearest && onto_items && src.location != FieldLocation::kGlobal &&
      (to_split != nullptr ||
       (from_split != nullptr && !(boundary_source && from_split->holds_whole_domain())));
  // Objects split alike: copied part to part when every target item of a part takes its value
  // from that part's items (item for item, or inside the part's own tets).
  if (alike && mapping_ != Mapping::kNearest &&
      (mapping_ == Mapping::kBarycentric || src.location == dst.location)) {
    split_ = from_split;
    agree_on_ = from_split;
    from_ = &from_split->local_part();
    to_ = &to_split->local_part();
    from_field_ = from_->FindField(src.name);
    to_field_ = to_->FindField(dst.name);
    src_pos = ItemRestPositions(*from_, src.location);
    dst_pos = ItemRestPositions(*to_, dst.location);
    Log().debug("{}: copies the parts of {} to those of {}, each process its own (split alike)",
                this->path(), from.path(), to.path());
  } else if (nearest_parts || (mapping_ == Mapping::kBarycentric && onto_items &&
                               (from_split != nullptr || to_split != nullptr))) {
    // Split differently, or one end whole on every process: a split target's part takes the
    // values at its own items; a split source's values come from the parts that hold the
    // points or the nearest items (PartitionedObject::InterpolateAtPoints, NearestAtPoints),
    // a whole source's from its own tets or items.
    if (to_split != nullptr) {
      agree_on_ = to_split;
      to_ = &to_split->local_part();
      to_field_ = to_->FindField(dst.name);
      dst_pos = ItemRestPositions(*to_, dst.location);
    }
    if (mapping_ == Mapping::kBarycentric && from_split != nullptr)
      interpolation_ = from_split->InterpolateAtPoints(dst_pos);
    else if (from_split != nullptr && !(boundary_source && from_split->holds_whole_domain()))
      interpolation_ = from_split->NearestAtPoints(src.location, dst_pos);
    Log().debug("{}: maps {} onto the items of {}, each process its own", this->path(), from.path(),
                to.path());
  }
  if (mapping_ == Mapping::kBarycentric && !interpolation_) {
    map_ = from_->MapFromNodes(dst_pos);
  } else if (mapping_ == Mapping::kNearest && !interpolation_) {
    map_ = PointMap::Nearest(src_pos, dst_pos);
  }
  if (!interpolation_) source_.resize(src.components, from_->FieldCount(from_field_));
  target_.resize(dst.components, to_->FieldCount(to_field_));
}

StepStatus FieldCopy::DoFire(double /*t*/) {
  // A source field's no-data marker (e.g. -1 for "never activated") is neither blended nor
  // scaled: an item that reads it, or whose interpolation touches it, gets the target field's
  // own marker if it declares one, else the source's marker unchanged.
  const std::optional<double> marker = from_->field_info(from_field_).no_data;
  if (interpolation_) {
    // Interpolated by the parts that hold the points, the marker kept and the correction made.
    interpolation_->Interpolate(from_field_, target_, marker);
  } else {
    from_->ReadField(from_field_, source_);
    if (split_ != nullptr && from_->field_info(from_field_).location == FieldLocation::kNode)
      split_->ShareOwnedNodeValues(source_);
    if (map_ && marker) {
      map_->ApplyMarked(source_, target_, *marker);
    } else if (map_) {
      map_->Apply(source_, target_);
      // The source's own interpolation where it is of higher order than the blend of the tet's
      // vertices (a MixedSolid's quadratic displacement).
      if (mapping_ == Mapping::kBarycentric)
        from_->CorrectInterpolated(from_field_, map_->indices(), map_->weights(), target_);
    } else {
      target_ = source_;
    }
  }
  if (marker) {
    const double written = to_->field_info(to_field_).no_data.value_or(*marker);
    for (Index i = 0; i < target_.size(); ++i) {
      double& v = target_.data()[i];
      v = v == *marker ? written : v * scale_;
    }
  } else if (scale_ != 1.0) {
    target_ *= scale_;
  }
  // Every process stops alike when copying parts (each sees its own).
  if (const auto bad = FirstNonFinite(target_, to_->field_info(to_field_).location, agree_on_))
    return StepStatus::Diverged("non-finite value transferred at item", bad->item, bad->value);
  to_->WriteField(to_field_, target_);
  return StepStatus::Ok();
}

void RegisterFieldCopy(TypeRegistry& registry) {
  registry.connectors.Register(
      "FieldCopy",
      [](const ConnectorBuildContext& ctx) -> std::unique_ptr<Connector> {
        ctx.CheckKeys({"from", "to", "mapping", "scale"});
        auto [from, from_field] = ctx.ObjectField("from");
        auto [to, to_field] = ctx.ObjectField("to");
        using Mapping = FieldCopy::Mapping;
        Mapping mapping = Mapping::kAuto;
        if (auto m = ctx.params.Find("mapping")) {
          std::string s = m->AsChoice({"auto", "direct", "barycentric", "nearest"});
          mapping = s == "direct"        ? Mapping::kDirect
                    : s == "barycentric" ? Mapping::kBarycentric
                    : s == "nearest"     ? Mapping::kNearest
                                         : Mapping::kAuto;
        }
        // "scale": a number (dimensionless) or "VALUE UNIT".
        WrittenQuantity scale{1.0, {}};
        if (auto node = ctx.params.Find("scale"))
          scale = ReadWrittenQuantity(
              *node, "a number, or a string \"VALUE UNIT\" (e.g. \"2 kPa/mV\")", "kPa/mV");
        try {
          return std::make_unique<FieldCopy>(ctx.name, *from, from_field, *to, to_field, mapping,
                                             scale.value, scale.unit);
        } catch (const InputError& e) {
          ctx.params.Fail(e.what());
        }
      },
      "volume coupling: Get a field of one object, map it, Set it on another");
  // A barycentric or nearest copy couples parts split any way (each process asks for the
  // values at its own target items); a direct one, or "auto" (which may turn out direct), those
  // of objects split alike.
  registry.connector_part_use["FieldCopy"] = [](const JsonNode& params) {
    const auto mapping = params.Find("mapping");
    const std::string name = mapping && mapping->is_string() ? mapping->AsString() : "auto";
    return name == "nearest" || name == "barycentric" ? TypeRegistry::PartUse::kAnyParts
                                                      : TypeRegistry::PartUse::kPartToPart;
  };
}

}  // namespace gipsi
