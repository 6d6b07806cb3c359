#pragma once
/// @file
/// `DistributedMonodomain`: the P1 monodomain (`Monodomain`, models/ep/monodomain.h) split over
/// the ranks of an MPI communicator, solved through PETSc. Each rank keeps its part of the mesh
/// (mesh_partition.h): the cell models, stimuli, clamps and activation/APD tracking run on its
/// local nodes with no communication (a node shared with another rank is stepped on both, from
/// the same voltage, so both hold the same state), and the diffusion step
///   (M + θΔt K) V⁺ = (M − (1 − θ)Δt K) V
/// is one global solve: K (and the consistent mass) as a PETSc MPIAIJ matrix assembled from the
/// ranks' tets (COO insertion, sums across ranks), the lumped mass as a Vec, V as a ghosted Vec
/// whose shared entries are refreshed from their owners after the solve, and a KSP with the
/// scene's settings (CG by default; preconditioner "jacobi", "amg" → PETSc's GAMG or "hypre" →
/// BoomerAMG), tolerance relative to ‖b‖ on the true (unpreconditioned) residual as in the
/// serial object. PETSc options with the prefix `ep_` (e.g. -ep_ksp_monitor, -ep_pc_type)
/// override them.
///
/// Node fields (V, activation_time, ...) are per local node, the element field `fibre` per local
/// tet (read-only, unlike the serial object's); the global fields
/// (activated_fraction, voltage_integral, diffusion_iterations) are reductions over the ranks,
/// so reading them is collective. A step that fails or diverges on one rank fails on every
/// rank (the others report which rank failed), so a coordinator that runs on every rank takes
/// the same decision everywhere.

#include <mpi.h>

#include <memory>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/models/ep/ep_tissue.h"
#include "gipsi/parallel/mesh_partition.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable or movable (a SimObject). Needs a ParallelSession for its whole lifetime. Its
/// checkpoints move to another partition (EpTissue's RowState).
class DistributedMonodomain final : public EpTissue {
 public:
  /// Collective: partitions `whole` (identical on every rank) over `comm`. Regions select
  /// nodes of the whole mesh, then each rank keeps its own; a fibre rule is solved over the
  /// ranks (TransmuralFibresOnPart), in both constructors. The diffusion solver is
  /// `params.distributed_linear` where set (the scene's "parallel" block), else `params.linear`.
  /// Throws InputError as Monodomain does (a region that selects no node of the whole mesh, on
  /// every rank), PetscError if PETSc fails.
  DistributedMonodomain(std::string name, const Mesh& whole, EpTissueParams params, MPI_Comm comm);
  /// Collective: on a mesh already cut (`part`, this rank's, e.g. from PartitionMeshBlocks, so
  /// that no rank held the mesh whole). Each rank selects the region nodes among its own, the
  /// geometric regions at the whole mesh's tolerance, node ids as whole-mesh indices, and a
  /// group's nodes as every rank found them (a rank may hold a node of a face group without
  /// the face's triangle). Throws
  /// InputError as above.
  DistributedMonodomain(std::string name, MeshPart part, EpTissueParams params, MPI_Comm comm);
  ~DistributedMonodomain() override;

  [[nodiscard]] std::string_view type_name() const override { return "Monodomain"; }
  [[nodiscard]] const Points& domain_positions() const override { return domain().nodes; }
  [[nodiscard]] const MeshPart& part() const { return part_; }
  [[nodiscard]] MPI_Comm comm() const { return comm_; }
  /// Fibre direction per local element.
  [[nodiscard]] const Points& fibres() const { return fibres_; }
  /// Name of the KSP and preconditioner in use, e.g. "cg + gamg".
  [[nodiscard]] std::string solver_name() const;
  /// A node field (one value per local node) gathered on rank 0 in the whole mesh's order;
  /// empty on the other ranks. Collective.
  [[nodiscard]] std::vector<double> Gather(const double* local) const {
    return GatherNodeValues(part_, local, comm_);
  }

 protected:
  StepStatus DoStep(double t, double dt) override;
  StepStatus SolveDiffusion(double dt_ms, double* v, int& iterations, std::string& detail) override;
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override;

 private:
  struct Petsc;
  DistributedMonodomain(std::string name, EpTissueParams params, MPI_Comm comm, MeshPart part,
                        const Mesh* whole);
  static const Mesh& CheckedDomain(const Mesh& whole);
  void Assemble();

  MPI_Comm comm_;
  MeshPart part_;
  Points fibres_;
  std::unique_ptr<Petsc> petsc_;
  FieldId f_fibre_, f_activated_, f_integral_, f_iterations_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
