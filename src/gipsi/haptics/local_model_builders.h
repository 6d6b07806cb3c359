#pragma once
/// @file
/// Builders of local dynamic models (local_model.h) from an object's full model, run by the
/// simulation at its own rate:
///  - `MassSpringNeighbourhood`: the contact node and the nodes within a few rings of springs
///    move, the next ring is held fixed; mass, damping and tangent stiffness of the springs
///    are linearised at the current state.
///  - `FemCondensation`: the FEM object's tangent stiffness (FemSolid::CalcStiffness at the
///    current state, constrained dofs eliminated) is factorised (CHOLMOD, symbolic analysis
///    kept between builds) and condensed at the contact node: K_c = (E_cᵀ K⁻¹ E_c)⁻¹, the 3×3
///    stiffness the tissue offers a point load there; the node keeps its lumped mass and the
///    object's Rayleigh damping (α m + β K_c).
/// Nodes with a constrained axis count as fixed.

#include <memory>
#include <vector>

#include "gipsi/haptics/local_model.h"
#include "gipsi/numerics/sparse/linear_solver.h"

namespace gipsi {

class SimObject;
class MassSpring;
class FemSolid;

/// Builds local models of one object at its current state. Not copyable; runs on the
/// simulation thread only.
class LocalModelBuilder {
 public:
  LocalModelBuilder() = default;
  LocalModelBuilder(const LocalModelBuilder&) = delete;
  LocalModelBuilder& operator=(const LocalModelBuilder&) = delete;
  virtual ~LocalModelBuilder() = default;

  /// The object the models describe.
  [[nodiscard]] virtual SimObject& object() = 0;
  /// Builds the model for contact at boundary vertex `vertex` with outward unit `normal`, the
  /// tool pushing with normal force `anchor_force` [N] at the current state, discretised for
  /// the haptic `period` [s]. Returns false (model inactive) if the vertex is constrained or
  /// the linearisation is singular.
  virtual bool Build(Index vertex, const Vec3& normal, double anchor_force, double period,
                     LocalDynamicModel& out) = 0;
};

/// Neighbourhood model of a MassSpring object.
class MassSpringNeighbourhood final : public LocalModelBuilder {
 public:
  /// `rings` ≥ 0: spring rings around the contact node that move (capped at kMaxLocalNodes
  /// nodes, nearest rings first; the nodes left out are held fixed).
  MassSpringNeighbourhood(MassSpring& object, int rings = 1);
  [[nodiscard]] SimObject& object() override;
  bool Build(Index vertex, const Vec3& normal, double anchor_force, double period,
             LocalDynamicModel& out) override;
  /// Domain nodes of the last model (contact node first).
  [[nodiscard]] const std::vector<int>& local_nodes() const { return local_; }

 private:
  MassSpring& object_;
  int rings_;
  std::vector<std::vector<int>> node_springs_;  // springs at each node
  std::vector<int> local_index_;                // node → local index or −1
  std::vector<int> local_;
  VecX xdot_;
};

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
