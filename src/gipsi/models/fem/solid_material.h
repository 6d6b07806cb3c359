#pragma once
/// @file
/// Solid constitutive laws (material family "solid") for the tetrahedral FEM object. A law maps
/// the deformation gradient F (3×3, reference → current) of an element to its strain energy
/// density W(F) [J/m³ = Pa], first Piola–Kirchhoff stress P = ∂W/∂F [Pa] and the tangent
/// dP/dF (9×9). All laws are frame-indifferent except the small-strain "Linear" law.
///
/// Index convention for dP/dF: F and P are flattened column-major, vec(F)[i + 3 j] = F(i, j),
/// and dPdF(i + 3 j, k + 3 l) = ∂P(i, j) / ∂F(k, l).

#include <Eigen/Core>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/core/material.h"
#include "gipsi/core/registry.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

using Mat9 = Eigen::Matrix<double, 9, 9>;
/// Stiffness matrix of one P1 tetrahedron: row 3a + i, column 3b + k (a, b local nodes).
using Mat12 = Eigen::Matrix<double, 12, 12>;
/// Shape-function gradients of a P1 tetrahedron, column a = ∇N_a [1/m].
using TetGradients = Eigen::Matrix<double, 3, 4>;

/// Per-element data a law may use besides F. Plain struct; copyable.
struct MaterialPoint {
  /// Orthonormal material axes in the reference configuration, as columns: fibre f, sheet s,
  /// sheet-normal n. Identity for isotropic laws.
  Mat3 axes = Mat3::Identity();
  /// Active tension Ta [Pa] along the fibre: adds the second Piola–Kirchhoff stress
  /// S_a = Ta f ⊗ f (energy Ta E_ff). Zero when not driven.
  double active_tension = 0;
};

/// Up to kLanes elements that SolidMaterial::ElementStressAndStiffnessBatch evaluates together,
/// stored lane-interleaved (entry k of element l at [k][l]) for vector code. The caller fills
/// count and the inputs of lanes 0..count−1; the law writes P, K and ok of those lanes (and may
/// compute unused lanes on copies of lane 0).
struct ElementBatch {
  static constexpr int kLanes = 4;
  int count = 0;  ///< elements in the batch, 1..kLanes
  // Inputs.
  alignas(32) double F[9][kLanes];   ///< deformation gradient, F(i, j) at [i + 3j]
  alignas(32) double g[12][kLanes];  ///< shape-function gradients, g(j, a) at [j + 3a]
  alignas(32) double volume[kLanes];
  MaterialPoint mp[kLanes];
  // Outputs.
  alignas(32) double P[9][kLanes];    ///< first Piola–Kirchhoff stress, P(i, j) at [i + 3j]
  alignas(32) double K[144][kLanes];  ///< element stiffness, K(r, c) at [r + 12c]
  bool ok[kLanes] = {};               ///< false where F is outside the law's domain

  /// Writes element `lane`'s inputs.
  void SetInput(int lane, const Mat3& f, const TetGradients& grad, double vol,
                const MaterialPoint& point);
  [[nodiscard]] Mat3 InputF(int lane) const;
  [[nodiscard]] TetGradients InputGradients(int lane) const;
  /// Writes element `lane`'s outputs.
  void SetOutput(int lane, bool success, const Mat3& stress, const Mat12& stiffness);
  [[nodiscard]] Mat3 OutputP(int lane) const;
  [[nodiscard]] Mat12 OutputK(int lane) const;
};

/// Base class of solid laws. Immutable after construction, shared by all elements; all methods
/// are const, thread-safe and allocation-free.
class SolidMaterial : public Material {
 public:
  [[nodiscard]] std::string_view family() const final { return "solid"; }

  /// Strain energy density W(F) [Pa]; +infinity where F is outside the law's domain (e.g.
  /// det F <= 0 for laws with ln J), so a line search can reject such states.
  [[nodiscard]] virtual double Energy(const Mat3& F, const MaterialPoint& mp) const = 0;
  /// P(F). Returns false (P unspecified) when F is outside the law's domain.
  [[nodiscard]] virtual bool Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const = 0;
  /// P(F) and dP/dF. Returns false when F is outside the law's domain.
  [[nodiscard]] virtual bool StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                              Mat9& dPdF) const = 0;

  /// P(F) and the stiffness of a P1 tetrahedron of rest volume `volume` [m³] and shape-function
  /// gradients `g`: K(3a + i, 3b + k) = V Σ_jl g(j, a) dPdF(i + 3j, k + 3l) g(l, b) = ∂f_a,i/∂x_b,k
  /// for the nodal forces f_a = V P g_a. Returns false when F is outside the law's domain. The
  /// default contracts StressAndTangent; a law with a cheaper closed form overrides it (the
  /// result must be the same matrix up to round-off).
  [[nodiscard]] virtual bool ElementStressAndStiffness(const Mat3& F, const MaterialPoint& mp,
                                                       const TetGradients& g, double volume,
                                                       Mat3& P, Mat12& K) const;

  /// ElementStressAndStiffness for the `batch.count` elements of a batch (the FEM assembly's
  /// path for tangents): ok[l] = ElementStressAndStiffness(F_l, mp_l, g_l, V_l, P_l, K_l). The
  /// default evaluates the elements one by one; a law may evaluate them together in vector lanes
  /// (CorotationalSolid), with the same results up to round-off.
  virtual void ElementStressAndStiffnessBatch(ElementBatch& batch) const;
  /// True if ElementStressAndStiffnessBatch is faster than the elements one by one (the law
  /// overrides it); the assembly then uses batches, otherwise it skips the batch's copies.
  [[nodiscard]] virtual bool has_batch_kernel() const { return false; }

  /// κ [Pa] if the law's energy is W(F) = W̃(F) + κ/2 (ln J)² with that volumetric term split
  /// off (NeoHookean: κ = λ; Guccione: its bulk modulus), else 0. The mixed displacement–
  /// pressure elements (mixed_solid.h) replace the term by an independent pressure field.
  [[nodiscard]] virtual double log_volumetric_modulus() const { return 0; }
  /// True if the law reads MaterialPoint::axes (a fibre field is required).
  [[nodiscard]] virtual bool needs_fibres() const { return false; }
  /// Small-strain Young's modulus [Pa] and Poisson ratio of the law at rest, for time-step
  /// estimates, wave speeds and solver scaling (for anisotropic laws, along the stiffest axis).
  [[nodiscard]] virtual double small_strain_youngs_modulus() const = 0;
  [[nodiscard]] virtual double small_strain_poisson_ratio() const = 0;
};

/// Registers the solid laws: "Linear", "Corotational", "StVenantKirchhoff", "NeoHookean",
/// "Guccione" (see solid_laws.h for their equations and JSON parameters).
void RegisterSolidLaws(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
