#pragma once
/// @file
/// `Monodomain`: cardiac bioelectricity on a tetrahedral mesh with linear (P1) finite elements —
/// GiPSi's "bioelectricity" simulation object. The equation, splitting and units are those of
/// `EpTissue` (ep_tissue.h); this class adds the P1 operators
///   K_ij = Σ_e V_e ∇φ_i · D_e ∇φ_j,   D_e = d_t I + (d_l − d_t) f_e f_eᵀ,
///   M_ij = Σ_e V_e (1 + δ_ij)/20  (consistent) or m_i = Σ_e V_e/4 (lumped),
/// with d = σ/(χ Cm) and a per-element fibre direction f_e (the writable element field "fibre";
/// writing it reassembles K). The domain does not move: EP runs on the reference configuration.

#include <memory>
#include <string>

#include "gipsi/base/export.h"
#include "gipsi/core/registry.h"
#include "gipsi/models/ep/ep_tissue.h"
#include "gipsi/numerics/p1_scalar.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable or movable (a SimObject).
class Monodomain final : public EpTissue {
 public:
  /// Throws InputError if the mesh has no tets or a degenerate one, if the conductivity is
  /// anisotropic without a fibre direction, or if a stimulus/clamp region selects no node.
  Monodomain(std::string name, std::shared_ptr<const Mesh> mesh, EpTissueParams params);

  [[nodiscard]] std::string_view type_name() const override { return "Monodomain"; }
  [[nodiscard]] const Points& domain_positions() const override { return domain().nodes; }
  /// Fibre direction per element (3 by E, unit vectors).
  [[nodiscard]] const Points& fibres() const { return fibres_; }

 protected:
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;
  void DoWriteField(FieldId id, const Eigen::Ref<const Eigen::MatrixXd>& in) override;

 private:
  void Assemble();

  Points fibres_;
  FieldId f_fibre_;
};

/// The P1 monodomain operators of `mesh` (coordinates in m, operators in mm) with the fibre
/// direction `fibres` per element (3 by E, unit) and the diffusivities of `params`; the
/// consistent mass too unless `params.lumped_mass`. Shared by Monodomain and the distributed
/// object (gipsi/parallel/). Throws InputError naming a degenerate tet.
P1ScalarOperators AssembleMonodomainOperators(const Mesh& mesh, const Points& fibres,
                                              const EpTissueParams& params);

/// Registers "Monodomain" (keys in docs/scene-format.md).
void RegisterMonodomain(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
