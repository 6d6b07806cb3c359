#pragma once
/// @file
/// `CavityLaw`: what the blood in a cavity (a ventricle) answers over one step, for the
/// monolithic coupling of a deforming wall to a lumped blood model. If the cavity pressure is
/// held at p over the step [t, t + dt], how much volume does the blood fill at the end of the
/// step? The wall model solves its own equations together with "wall volume = blood volume"
/// (pressure as the unknown that closes it), so the stiff isovolumetric phases, where a closed
/// valve makes the blood volume independent of p, neither oscillate nor need iterations between
/// the two objects. A connector implements the law for its blood object and attaches it to the
/// wall object (SimObject::AttachCavityLaw).

namespace gipsi {

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

}  // namespace gipsi
