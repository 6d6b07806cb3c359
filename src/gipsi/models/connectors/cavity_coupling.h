#pragma once
/// @file
/// `CavityCoupling`: the muscle ↔ blood coupling of the GiPSi heart through their shared
/// boundary, the endocardium. The wall object (e.g. a FemSolid with a declared cavity) solves
/// its step together with "enclosed volume = blood volume", with the cavity pressure as the
/// unknown (cavity_law.h); this connector answers the wall's question "how much volume does the
/// blood fill at the end of the step if the pressure is p?" by a trial integration of the lumped
/// circulation whose chamber is pressure-driven, and after the wall's step hands the solved
/// pressure to that chamber, so the blood's real step ends with exactly the volume the wall
/// encloses. Isovolumetric phases (both valves closed) need no special treatment: the blood
/// volume is then fixed and the pressure is its multiplier.
///
/// Semantics and units:
///   Gets   wall  "<cavity>_volume" [m³] (once, at build: the chamber starts with it)
///          wall  "<cavity>_pressure" [Pa] (each firing: the pressure the wall solved)
///   Sets   blood "<chamber>_pressure_input" [Pa] (each firing)
///   Law    V_cavity(p) = V_blood(p) (1 − p / K), V_blood from the circulation's trial step and
///          K the blood's bulk modulus (2.2 GPa by default): blood is slightly compressible,
///          which keeps the pressure a well-defined function of the wall's volume when both
///          valves are closed (a 100 mL cavity at 16 kPa is compressed by 0.7 µL).
/// Ports: the wall's "cavity wall" capability and its two fields above (read), the blood's
/// "lumped chambers" capability and its pressure input (written).
/// Order: the wall steps, then the connector fires, then the blood steps, with the same time
/// step, every macro step; the coordinator refuses any other schedule before the first step
/// (and a step that still finds them out of order fails rather than going on).

#include <string>

#include "gipsi/base/export.h"
#include "gipsi/core/cavity_law.h"
#include "gipsi/core/connector.h"
#include "gipsi/core/registry.h"
#include "gipsi/core/sim_object.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable or movable (a Connector).
class CavityCoupling final : public Connector, public CavityLaw {
 public:
  /// Attaches itself to `wall`'s cavity `cavity` and sets `blood`'s chamber `chamber` (which
  /// must be pressure-driven) to the cavity's current volume. Throws InputError for a wall
  /// without cavities (CavityWall) or without this one, blood without lumped chambers
  /// (LumpedChambers) or without this pressure-driven chamber, or a bulk modulus ≤ 0.
  CavityCoupling(std::string name, SimObject& wall, const std::string& cavity, SimObject& blood,
                 const std::string& chamber, double bulk_modulus);

  [[nodiscard]] std::string_view type_name() const override { return "CavityCoupling"; }
  bool EndVolume(double t, double dt, double p, double& volume) override;
  /// Trial integrations of the blood so far (what the coupling costs the circulation).
  [[nodiscard]] std::int64_t trials() const { return trials_; }
  /// Nothing of the future lives here (the pressure is the wall's, the volumes the blood's).

 protected:
  StepStatus DoFire(double t) override;

 private:
  SimObject& wall_;
  SimObject& blood_;
  LumpedChambers& chambers_;
  int chamber_ = -1;
  FieldId wall_pressure_, blood_pressure_;
  double bulk_modulus_;
  std::int64_t trials_ = 0;
};

/// Registers "CavityCoupling" (keys in docs/scene-format.md).
void RegisterCavityCoupling(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
