#include "gipsi/models/connectors/cavity_coupling.h"

#include <cmath>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/units.h"

namespace gipsi {

CavityCoupling::CavityCoupling(std::string name, SimObject& wall, const std::string& cavity,
                               SimObject& blood, const std::string& chamber, double bulk_modulus)
    : Connector(std::move(name)),
      wall_(wall),
      blood_(blood),
      chambers_(LumpedChambersOf(blood)),
      bulk_modulus_(bulk_modulus) {
  BindNoState();  // the pressure is the wall's state, the volumes the blood's
  if (!(bulk_modulus_ > 0))
    throw InputError(
        fmt::format("connector '{}': the blood bulk modulus must be positive", this->path()));
  chamber_ = chambers_.FindPressureDrivenChamber(chamber);
  // Throws for an object without cavities, or without this one.
  CavityWallOf(wall_).AttachCavityLaw(cavity, this);
  UseCapability("wall", wall_, "cavity wall");
  UseField("wall", wall_, cavity + "_volume", FieldAccess::kRead, "m^3", 1);
  UseField("wall", wall_, cavity + "_pressure", FieldAccess::kRead, "Pa", 1);
  UseCapability("blood", blood_, "lumped chambers");
  UseField("blood", blood_, chamber + "_pressure_input", FieldAccess::kWrite, "Pa", 1);
  RequireOrder({&wall_, &blood_, true, "the blood integrates with the pressure the wall solved"});
  const FieldId volume = wall_.FindField(cavity + "_volume");
  wall_pressure_ = wall_.FindField(cavity + "_pressure");
  blood_pressure_ = blood_.FindField(chamber + "_pressure_input");
  // The chamber starts with the blood that fills the wall's cavity at the wall's pressure.
  Eigen::Matrix<double, 1, 1> v, p;
  wall_.ReadField(volume, v);
  wall_.ReadField(wall_pressure_, p);
  const double blood_volume = v(0, 0) / (1 - p(0, 0) / bulk_modulus_);
  Log().info("connector '{}': chamber '{}' starts with the cavity's {:.2f} mL (was {:.2f} mL)",
             this->path(), chamber, 1e6 * blood_volume, 1e6 * chambers_.chamber_volume(chamber_));
  chambers_.SetChamberVolume(chamber_, blood_volume);
  blood_.WriteField(blood_pressure_, p);
}

bool CavityCoupling::EndVolume(double t, double dt, double p, double& volume) {
  // The blood must still be at the start of the wall's step (it steps after the wall).
  if (std::abs(blood_.time() - t) > 1e-9 * std::max(1.0, std::abs(t))) return false;
  ++trials_;
  double blood_volume = 0;
  if (!chambers_.PredictChamberVolume(chamber_, dt, p, blood_volume)) return false;
  volume = blood_volume * (1 - p / bulk_modulus_);
  return true;
}

StepStatus CavityCoupling::DoFire(double /*t*/) {
  if (!(wall_.time() > blood_.time()))
    return StepStatus::Failed(
        "fired out of order: it must fire after the wall's step and before the blood's (list "
        "it between them in the order)");
  Eigen::Matrix<double, 1, 1> p;
  wall_.ReadField(wall_pressure_, p);
  if (!std::isfinite(p(0, 0)))
    return StepStatus::Diverged("non-finite cavity pressure", 0, p(0, 0));
  blood_.WriteField(blood_pressure_, p);
  return StepStatus::Ok();
}

void RegisterCavityCoupling(TypeRegistry& registry) {
  registry.connectors.Register(
      "CavityCoupling",
      [](const ConnectorBuildContext& ctx) -> std::unique_ptr<Connector> {
        ctx.CheckKeys({"wall", "cavity", "blood", "chamber", "blood_bulk_modulus"});
        const JsonNode& p = ctx.params;
        SimObject& wall = ctx.Object("wall");
        try {
          (void)CavityWallOf(wall);
        } catch (const InputError& e) {
          p.At("wall").Fail(e.what());
        }
        SimObject& blood = ctx.Object("blood");
        try {
          (void)LumpedChambersOf(blood);
        } catch (const InputError& e) {
          p.At("blood").Fail(e.what());
        }
        double bulk = 2.2e9;
        if (auto k = p.Find("blood_bulk_modulus")) bulk = ReadPositiveQuantity(*k, "Pa");
        try {
          return std::make_unique<CavityCoupling>(ctx.name, wall, p.At("cavity").AsString(), blood,
                                                  p.At("chamber").AsString(), bulk);
        } catch (const InputError& e) {
          p.Fail(e.what());
        }
      },
      "boundary coupling: cavity volume <-> lumped blood pressure (monolithic, "
      "isovolumetric-safe)");
  // The wall's cavity (a capability) and its global volume and pressure: a wall made in blocks
  // answers them as a whole one does.
  registry.connector_part_use["CavityCoupling"] = [](const JsonNode&) {
    return TypeRegistry::PartUse::kGlobal;
  };
}

}  // namespace gipsi
