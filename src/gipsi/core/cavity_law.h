#pragma once
/// @file
/// `CavityLaw`: what the blood in a cavity (a ventricle) answers over one step, for the
/// monolithic coupling of a deforming wall to a lumped blood model. If the cavity pressure is
/// held at p over the step [t, t + dt], how much volume does the blood fill at the end of the
/// step? The wall model solves its own equations together with "wall volume = blood volume"
/// (pressure as the unknown that closes it), so the stiff isovolumetric phases, where a closed
/// valve makes the blood volume independent of p, neither oscillate nor need iterations between
/// the two objects. A connector implements the law for its blood object and attaches it to the
/// wall object through the wall's `CavityWall` capability.

#include <string>
#include <string_view>
#include <vector>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class SimObject;

/// Interface; implementations are owned by connectors and outlive the attachment.
class CavityLaw {
 public:
  virtual ~CavityLaw() = default;
  /// The volume [m³] the blood occupies at t + dt if the cavity pressure is p [Pa] over
  /// [t, t + dt], starting from the blood model's state at t. Non-increasing in p (more pressure
  /// pushes more blood out, and compresses it). False if the blood model cannot answer (its
  /// state is not at t, or it fails); then `volume` is unspecified. Must not allocate or throw.
  virtual bool EndVolume(double t, double dt, double p, double& volume) = 0;
};

/// Capability of an object whose boundary encloses cavities (e.g. a ventricle's endocardium,
/// declared in its scene entry): a connector couples a cavity to a blood model through it.
/// Objects that have cavities implement it beside SimObject (FemSolid, MassSpring); a connector
/// asks for it with CavityWallOf, so no other object type carries cavity code.
class CavityWall {
 public:
  virtual ~CavityWall() = default;
  /// The names of its cavities, in declaration order (possibly none).
  [[nodiscard]] virtual std::vector<std::string> cavity_names() const = 0;
  /// Couples cavity `cavity` to blood: from now on each step solves for the cavity pressure
  /// that makes the wall's enclosed volume equal `law`'s end volume. `law` must outlive the
  /// object's steps. Throws InputError (naming the object and listing its cavities) if there
  /// is no such cavity, or if the object cannot couple it (e.g. it is already coupled).
  virtual void AttachCavityLaw(std::string_view cavity, CavityLaw* law) = 0;
};

/// Capability of a lumped (0D) blood model whose chambers can take their pressure from a wall
/// (Circulation's chambers with "driven_by": "pressure"): the blood side of a cavity coupling,
/// which asks for it with LumpedChambersOf, so the coupling needs no concrete blood type.
class LumpedChambers {
 public:
  virtual ~LumpedChambers() = default;
  /// The index of the pressure-driven chamber `name`. Throws InputError naming the object if it
  /// has no such chamber or the chamber is not pressure-driven (listing those that are).
  [[nodiscard]] virtual int FindPressureDrivenChamber(std::string_view name) const = 0;
  /// The blood volume [m³] of chamber `chamber` (an index from FindPressureDrivenChamber).
  [[nodiscard]] virtual double chamber_volume(int chamber) const = 0;
  /// Sets it (before the first step: the wall's cavity volume).
  virtual void SetChamberVolume(int chamber, double volume) = 0;
  /// The chamber's blood volume [m³] at time() + dt if its pressure is held at p [Pa] over the
  /// step, integrated exactly as the object's Step would, leaving the object unchanged. False
  /// if the integration fails. Must not throw, nor allocate after its first call.
  virtual bool PredictChamberVolume(int chamber, double dt, double p, double& volume) = 0;
};

/// `object` as lumped chambers. Throws InputError ("object 'NAME' (TYPE) has no lumped
/// chambers …") for an object type without the capability.
LumpedChambers& LumpedChambersOf(SimObject& object);

/// `object` as a cavity wall. Throws InputError ("object 'NAME' (TYPE) has no cavities to
/// couple to blood") for an object type without the capability.
CavityWall& CavityWallOf(SimObject& object);

}  // namespace gipsi
GIPSI_EXPORT_END
