#pragma once
/// @file
/// The solid constitutive laws (family "solid") registered by RegisterSolidLaws. Conventions of
/// solid_material.h: F is the 3×3 deformation gradient (dimensionless), W [Pa = J/m³], the first
/// Piola–Kirchhoff stress P = ∂W/∂F [Pa] and dP/dF (9×9, column-major vec(F)[i + 3 j] = F(i, j)).
/// Notation: J = det F, C = FᵀF, E = ½(C − I) (Green–Lagrange strain), S the second
/// Piola–Kirchhoff stress (P = F S), λ and μ the Lamé parameters, A : B = Σ A_ij B_ij.
///
/// Active tension (every law). With fibre f = MaterialPoint::axes.col(0) and Ta =
/// MaterialPoint::active_tension [Pa], every law adds
///   W_a = Ta E_ff = Ta/2 (|F f|² − 1),   S_a = Ta f ⊗ f,   P_a = F S_a,   δP_a = δF S_a,
/// the usual active-stress decomposition of cardiac mechanics (e.g. Nash & Panfilov, "Electro-
/// mechanical model of excitable tissue to study reentrant cardiac arrhythmias", Prog. Biophys.
/// Mol. Biol. 85, 2004).
///
/// Laws and JSON parameters ("material": {"law": NAME, ...}):
///  - "Linear", "Corotational", "StVenantKirchhoff", "NeoHookean": `youngs_modulus` E > 0 [Pa],
///    `poisson_ratio` ν ∈ (−1, 0.5) (0.5, incompressibility, is rejected), giving
///    λ = E ν / ((1 + ν)(1 − 2ν)) and μ = E / (2 (1 + ν)).
///  - "Guccione": `C` [Pa], `bf`, `bt`, `bfs` (dimensionless), `bulk_modulus` κ [Pa], all > 0
///    and required; needs a fibre field.
/// Textbook references for the isotropic laws: Bonet & Wood, "Nonlinear Continuum Mechanics for
/// Finite Element Analysis", 2nd ed., Cambridge 2008 (ch. 6); Sifakis & Barbič, "FEM
/// simulation of 3D deformable solids", SIGGRAPH 2012 course notes (corotational).
///
/// Domain. Laws with ln J (NeoHookean, Guccione) are defined for J > kMinJacobian only: there
/// Energy is +infinity and Stress/StressAndTangent return false. Every Stress/StressAndTangent
/// also returns false rather than produce a non-finite P or dP/dF (e.g. e^Q overflow in
/// Guccione). Linear, Corotational and StVenantKirchhoff are defined for every finite F,
/// including inverted elements (det F ≤ 0).

#include <string_view>

#include "gipsi/base/export.h"
#include "gipsi/models/fem/solid_material.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Smallest J = det F accepted by the laws with ln J (dimensionless).
inline constexpr double kMinJacobian = 1e-12;

/// Lamé parameters [Pa].
struct LameParameters {
  double lambda = 0;  ///< first Lamé parameter λ [Pa]
  double mu = 0;      ///< shear modulus μ [Pa]
};

/// λ = E ν / ((1 + ν)(1 − 2ν)), μ = E / (2 (1 + ν)) from Young's modulus E > 0 [Pa] and Poisson
/// ratio ν ∈ (−1, 0.5). Preconditions checked (aborts otherwise).
[[nodiscard]] LameParameters LameFromYoungPoisson(double youngs_modulus, double poisson_ratio);

/// Rotation-variant ("signed") SVD F = U diag(sigma) Vᵀ with U, V proper rotations (det = +1),
/// sigma sorted by decreasing magnitude and only sigma(2) possibly negative (when det F < 0):
/// Irving, Teran & Fedkiw, "Invertible finite elements for robust simulation of large
/// deformation", SCA 2004. R = U Vᵀ is then the rotation of the polar decomposition
/// F = R S, S = V diag(sigma) Vᵀ symmetric. Uses Eigen::JacobiSVD on fixed-size matrices (no
/// allocation). For a non-finite F, sigma is NaN and U = V = I.
void SignedSvd(const Mat3& F, Mat3& U, Vec3& sigma, Mat3& V);

/// Laws parameterised by Young's modulus and Poisson ratio (isotropic).
class IsotropicSolid : public SolidMaterial {
 public:
  /// E > 0 [Pa], ν ∈ (−1, 0.5); preconditions checked (the JSON factories validate first).
  IsotropicSolid(double youngs_modulus, double poisson_ratio);
  [[nodiscard]] double small_strain_youngs_modulus() const final { return youngs_modulus_; }
  [[nodiscard]] double small_strain_poisson_ratio() const final { return poisson_ratio_; }
  [[nodiscard]] double lambda() const { return lame_.lambda; }  ///< λ [Pa]
  [[nodiscard]] double mu() const { return lame_.mu; }          ///< μ [Pa]

 protected:
  double youngs_modulus_;  ///< E [Pa]
  double poisson_ratio_;   ///< ν
  LameParameters lame_;    ///< λ, μ [Pa] from E and ν
};

/// "Linear": small-strain isotropic elasticity (not frame-indifferent: a rigid rotation
/// stresses it). ε = ½(F + Fᵀ) − I,
///   W = μ ε:ε + λ/2 (tr ε)²,   P = σ = λ tr(ε) I + 2μ ε,
///   dP_ij/dF_kl = λ δ_ij δ_kl + μ (δ_ik δ_jl + δ_il δ_jk)   (constant),
/// plus the active term. Defined for every F.
class LinearSolid final : public IsotropicSolid {
 public:
  LinearSolid(double youngs_modulus, double poisson_ratio);
  [[nodiscard]] std::string_view law() const override { return "Linear"; }
  [[nodiscard]] double Energy(const Mat3& F, const MaterialPoint& mp) const override;
  [[nodiscard]] bool Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const override;
  [[nodiscard]] bool StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                      Mat9& dPdF) const override;

 private:
  Mat9 tangent_;  // the constant passive dP/dF
};

/// "Corotational" (Müller & Gross, "Interactive virtual materials", GI 2004; the energy form of
/// Sifakis & Barbič 2012). Polar decomposition F = R S by SignedSvd (R a proper rotation
/// even for det F < 0, Irving et al. 2004), singular values σ_i:
///   W = μ ‖F − R‖² + λ/2 (tr(RᵀF − I))² = μ Σ (σ_i − 1)² + λ/2 (Σ σ_i − 3)²,
///   P = 2μ (F − R) + λ tr(RᵀF − I) R,
///   δP = 2μ (δF − δR) + λ (R:δF) R + λ tr(RᵀF − I) δR.
/// Rotation variation: δR = R [w]×, where (tr(S) I − S) w = axial(RᵀδF − δFᵀR), from
/// RᵀδF = [w]× S + δS and the identity S [w]× + [w]× S = [(tr(S) I − S) w]× for symmetric S.
/// In the V basis tr(S) I − S = V diag(σ₂ + σ₃, σ₁ + σ₃, σ₁ + σ₂) Vᵀ; these sums are ≥ 0 with the
/// signed SVD and vanish only for an inverted element with σ₂ = −σ₃ (or a collapsed one), where
/// R is not differentiable. Each sum is clamped to at least kMinSingularSum, so the tangent stays
/// finite there (entries ≲ (2μ + λ |tr(S − I)|) / kMinSingularSum). Defined for every F.
/// Speed: where det F is comfortably positive (every element that is not nearly inverted), R
/// comes from a scaled Newton polar iteration and (tr(S) I − S)⁻¹ from a direct 3×3 inverse,
/// several times faster than the SVD, which remains the path for (nearly) inverted elements.
class CorotationalSolid final : public IsotropicSolid {
 public:
  /// Lower bound on σ_i + σ_j in the tangent's rotation term (dimensionless).
  static constexpr double kMinSingularSum = 1e-6;

  CorotationalSolid(double youngs_modulus, double poisson_ratio);
  [[nodiscard]] std::string_view law() const override { return "Corotational"; }
  [[nodiscard]] double Energy(const Mat3& F, const MaterialPoint& mp) const override;
  [[nodiscard]] bool Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const override;
  [[nodiscard]] bool StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                      Mat9& dPdF) const override;
  /// Closed form of the element stiffness (no 9×9 tangent): with q_a = R g_a, X_a = R [g_a]×,
  /// M = (tr(S) I − S)⁻¹ (clamped as above) and c = λ tr(S − I) − 2μ,
  ///   K_ab = V [(2μ g_a·g_b + g_a·S_a g_b) I + λ q_a q_bᵀ + c X_a M X_bᵀ]
  /// (S_a the active PK2 stress), from δR g_a = −R [g_a]× M [g_b]× Rᵀ δx_b; symmetric
  /// blocks, so only a ≤ b are formed.
  [[nodiscard]] bool ElementStressAndStiffness(const Mat3& F, const MaterialPoint& mp,
                                               const TetGradients& g, double volume, Mat3& P,
                                               Mat12& K) const override;
  /// The same closed form for four elements at once, one per vector lane (AVX where the
  /// processor has it, numerics/simd.h; the same bits either way), and equal to the element-wise
  /// ElementStressAndStiffness up to round-off: the polar iteration runs in the lanes until
  /// every lane has converged, each lane keeping its own converged iterate. Lanes the fast path
  /// does not cover (a nearly inverted or non-finite F, a polar iteration that does not
  /// converge, an active tension) are evaluated element-wise.
  void ElementStressAndStiffnessBatch(ElementBatch& batch) const override;
  [[nodiscard]] bool has_batch_kernel() const override { return true; }

 private:
  /// R of the polar decomposition, tr(S) − 3 and M = (tr(S) I − S)⁻¹ (clamped); false for a
  /// non-finite F.
  [[nodiscard]] bool RotationAndInverse(const Mat3& F, Mat3& R, double& tr, Mat3& inv) const;
};

/// "StVenantKirchhoff" (Bonet & Wood 2008, ch. 6): E = ½(FᵀF − I),
///   W = μ E:E + λ/2 (tr E)²,   S = λ tr(E) I + 2μ E,   P = F S,
///   dP_ij/dF_kl = δ_ik S_lj + λ F_ij F_kl + μ ((F Fᵀ)_ik δ_jl + F_il F_kj).
/// Defined for every F (it softens and eventually fails under strong compression, a known
/// limitation of the law, not a domain restriction).
class StVenantKirchhoffSolid final : public IsotropicSolid {
 public:
  StVenantKirchhoffSolid(double youngs_modulus, double poisson_ratio);
  [[nodiscard]] std::string_view law() const override { return "StVenantKirchhoff"; }
  [[nodiscard]] double Energy(const Mat3& F, const MaterialPoint& mp) const override;
  [[nodiscard]] bool Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const override;
  [[nodiscard]] bool StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                      Mat9& dPdF) const override;
};

/// "NeoHookean", compressible (Bonet & Wood 2008, ch. 6), with H = F⁻ᵀ:
///   W = μ/2 (tr(FᵀF) − 3) − μ ln J + λ/2 (ln J)²,   P = μ (F − H) + λ ln J H,
///   dP_ij/dF_kl = μ δ_ik δ_jl + (μ − λ ln J) H_il H_kj + λ H_ij H_kl,
/// using ∂H_ij/∂F_kl = −H_il H_kj. Domain J > kMinJacobian.
class NeoHookeanSolid final : public IsotropicSolid {
 public:
  NeoHookeanSolid(double youngs_modulus, double poisson_ratio);
  [[nodiscard]] std::string_view law() const override { return "NeoHookean"; }
  [[nodiscard]] double log_volumetric_modulus() const override { return lame_.lambda; }
  [[nodiscard]] double Energy(const Mat3& F, const MaterialPoint& mp) const override;
  [[nodiscard]] bool Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const override;
  [[nodiscard]] bool StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                      Mat9& dPdF) const override;
  /// Closed form of the element stiffness: with h_a = H g_a (the current gradients),
  ///   K_ab = V [μ (g_a·g_b) I + (μ − λ ln J) h_b h_aᵀ + λ h_a h_bᵀ]
  /// (an active tension adds its geometric term through the generic contraction).
  [[nodiscard]] bool ElementStressAndStiffness(const Mat3& F, const MaterialPoint& mp,
                                               const TetGradients& g, double volume, Mat3& P,
                                               Mat12& K) const override;
  /// The same closed form for four elements in vector lanes (see CorotationalSolid's); lanes
  /// with J ≤ kMinJacobian, a non-finite result or an active tension go element-wise.
  void ElementStressAndStiffnessBatch(ElementBatch& batch) const override;
  [[nodiscard]] bool has_batch_kernel() const override { return true; }
};

/// Parameters of the Guccione law.
struct GuccioneParams {
  double C = 0;             ///< stiffness scale C > 0 [Pa]
  double bf = 0;            ///< fibre exponent b_f > 0 (dimensionless)
  double bt = 0;            ///< transverse (sheet–normal plane) exponent b_t > 0
  double bfs = 0;           ///< fibre–cross-fibre shear exponent b_fs > 0
  double bulk_modulus = 0;  ///< volumetric penalty κ > 0 [Pa]
};

/// "Guccione": transversely isotropic exponential law of passive myocardium (Guccione, McCulloch
/// & Waldman, "Passive material properties of intact ventricular myocardium determined from a
/// cylindrical model", J. Biomech. Eng. 113, 1991; Guccione, Costa & McCulloch, "Finite element
/// stress analysis of left ventricular mechanics in the beating dog heart", J. Biomech. 28, 1995)
/// with a volumetric penalty. With A = MaterialPoint::axes (columns f, s, n) and E' = Aᵀ E A:
///   Q = b_f E'_ff² + b_t (E'_ss² + E'_nn² + E'_sn² + E'_ns²) + b_fs (E'_fs² + E'_sf² + E'_fn²
///       + E'_nf²) = Σ_ab B_ab E'_ab²,
///   B = [[b_f, b_fs, b_fs], [b_fs, b_t, b_t], [b_fs, b_t, b_t]]  (rows and columns f, s, n),
///   W = C/2 (e^Q − 1) + κ/2 (ln J)²,
///   S = A S' Aᵀ,  S' = C e^Q (B ∘ E')  (∘ the entrywise product),   P = F S + κ ln J F⁻ᵀ.
/// Tangent: in Voigt form with engineering shears (ε' = [E'_ff, E'_ss, E'_nn, 2E'_sn, 2E'_fn,
/// 2E'_fs]), dS'/dε' = C e^Q (diag(b_f, b_t, b_t, b_t/2, b_fs/2, b_fs/2) + 2 s sᵀ) where s is the
/// Voigt vector of B ∘ E'; it is pushed to dP/dF with dε'/dF (so no 4th-order rotation is
/// formed), plus δF S and the volumetric term κ (H_ij H_kl − ln J H_il H_kj), H = F⁻ᵀ.
/// Domain J > kMinJacobian and Q ≤ kMaxExponent (beyond it e^Q nears overflow: Energy is
/// +infinity and Stress returns false).
///
/// Small-strain moduli (linearising at F = I: e^Q − 1 ≈ Q, ln J ≈ tr ε). The normal stiffness
/// in the fibre basis is K = κ 𝟙𝟙ᵀ + diag(d_f, d_t, d_t), d_f = C b_f, d_t = C b_t; shear moduli
/// G_fs = G_fn = C b_fs / 2, G_sn = C b_t / 2. The unconfined uniaxial moduli 1 / (K⁻¹)_aa are
///   E_f = (d_f d_t + κ d_t + 2κ d_f) / (d_t + 2κ)                     (along the fibre),
///   E_t = d_t (d_f d_t + κ d_t + 2κ d_f) / (d_f d_t + κ d_t + κ d_f)   (across it),
/// and small_strain_youngs_modulus() = max(E_f, E_t) (the stiffest axis, normally the fibre;
/// E_f → C (b_f + b_t / 2) as κ → ∞). small_strain_poisson_ratio() is that of the isotropic
/// material with this Young's modulus E and the law's linearised bulk modulus
/// K = κ + C (b_f + 2 b_t) / 9:  ν = (3K − E) / (6K) ∈ (−1, 0.5) (equivalently, bulk modulus K
/// against the equivalent shear modulus G = 3KE / (9K − E)); ν → 0.5 as κ / C → ∞.
class GuccioneSolid final : public SolidMaterial {
 public:
  /// Largest Q accepted (e^700 ≈ 1e304 is near the largest double).
  static constexpr double kMaxExponent = 700;

  /// All parameters > 0; preconditions checked (the JSON factory validates first).
  explicit GuccioneSolid(const GuccioneParams& params);
  [[nodiscard]] std::string_view law() const override { return "Guccione"; }
  [[nodiscard]] const GuccioneParams& params() const { return params_; }
  [[nodiscard]] bool needs_fibres() const override { return true; }
  [[nodiscard]] double log_volumetric_modulus() const override { return params_.bulk_modulus; }
  [[nodiscard]] double small_strain_youngs_modulus() const override { return small_e_; }
  [[nodiscard]] double small_strain_poisson_ratio() const override { return small_nu_; }
  [[nodiscard]] double Energy(const Mat3& F, const MaterialPoint& mp) const override;
  [[nodiscard]] bool Stress(const Mat3& F, const MaterialPoint& mp, Mat3& P) const override;
  [[nodiscard]] bool StressAndTangent(const Mat3& F, const MaterialPoint& mp, Mat3& P,
                                      Mat9& dPdF) const override;
  /// Closed form of the element stiffness (no 9×9 tangent): with r_a = Aᵀ g_a, G = F A, the
  /// 6×3 strain–displacement matrix B_a (row (m, n) = w (G(:, m) r_a(n) + G(:, n) r_a(m))ᵀ,
  /// w ½ on the normal rows), τ_a = B_aᵀ s and h_a = H g_a:
  ///   K_ab = V [C e^Q (B_aᵀ diag(d) B_b + 2 τ_a τ_bᵀ) + (g_a·S g_b) I
  ///             + κ (h_a h_bᵀ − ln J h_b h_aᵀ)],
  /// the contraction of StressAndTangent's terms with the shape gradients (S includes the
  /// active stress).
  [[nodiscard]] bool ElementStressAndStiffness(const Mat3& F, const MaterialPoint& mp,
                                               const TetGradients& g, double volume, Mat3& P,
                                               Mat12& K) const override;
  /// The same closed form for four elements in vector lanes, active tension included; lanes
  /// outside the domain or with a non-finite result go element-wise.
  void ElementStressAndStiffnessBatch(ElementBatch& batch) const override;
  [[nodiscard]] bool has_batch_kernel() const override { return true; }

 private:
  GuccioneParams params_;
  Mat3 b_;  // the exponent matrix B
  double small_e_;
  double small_nu_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
