#pragma once
/// @file
/// `FemCondensation`: FemSolid's haptic local model (gipsi/core/local_model.h). The object's
/// tangent stiffness (FemSolid::CalcStiffness at the current state, constrained dofs
/// eliminated) is factorised (CHOLMOD, symbolic analysis kept between builds) and condensed at
/// the contact node: K_c = (E_cᵀ K⁻¹ E_c)⁻¹, the 3×3 stiffness the tissue offers a point load
/// there; the node keeps its lumped mass and the object's Rayleigh damping (α m + β K_c). Nodes
/// with a constrained axis count as fixed. Registered for "FemSolid" by RegisterFemSolid.

#include <cstdint>
#include <memory>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/local_model.h"
#include "gipsi/numerics/sparse/linear_solver.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

class FemSolid;

/// Condensation of a FemSolid at the contact node.
class FemCondensation final : public LocalModelBuilder {
 public:
  explicit FemCondensation(FemSolid& object);
  [[nodiscard]] SimObject& object() override;
  bool Build(Index vertex, const Vec3& normal, double anchor_force, double period,
             LocalDynamicModel& out) override;
  /// The condensed 3×3 stiffness of the last build [N/m].
  [[nodiscard]] const Mat3& condensed_stiffness() const { return condensed_; }
  /// Number of numeric factorisations so far.
  [[nodiscard]] std::int64_t num_factorisations() const { return factorisations_; }

 private:
  FemSolid& object_;
  VecX lumped_mass_;  // per node
  SparseMatrix k_;
  std::vector<std::uint8_t> fixed_, analysed_fixed_;  // per dof
  std::unique_ptr<LinearSolver> solver_;              // CHOLMOD
  VecX rhs_, solution_;
  bool analysed_ = false;
  Mat3 condensed_ = Mat3::Zero();
  std::int64_t factorisations_ = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
