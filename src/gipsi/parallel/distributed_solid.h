#pragma once
/// @file
/// `DistributedSolid`: a `FemSolid` split over the ranks of an MPI communicator through PETSc
/// (the SolidDistribution a FemSolid on one rank's part of the mesh is given;
/// models/fem/solid_distribution.h). The mesh is cut as for the monodomain (mesh_partition.h):
/// each rank's FemSolid loops over its own tets, shared nodes' residual entries are summed
/// across the ranks through a ghosted PETSc Vec (block size 3), Newton's norms are MPI
/// reductions, and every Newton correction is one PETSc solve of the whole tangent:
///   - the ranks' partial tangents summed into an MPIAIJ matrix (block size 3) by COO
///     insertion, the index arrays set up once per pattern;
///   - KSP as the object's linear_solver says: "cg" with "amg" (PETSc's GAMG, given the
///     rigid-body modes of the rest shape as its near-null space: MatNullSpaceCreateRigidBody),
///     "hypre" (BoomerAMG), "jacobi" (3×3 point-block Jacobi), "sgs" (each rank's local
///     symmetric SOR) or "none"; "cholmod"/"ldlt" → MUMPS's symmetric LDLᵀ (indefinite
///     tangents too), "umfpack" → MUMPS's LU. CG stops at `tolerance` relative to ‖b‖ on the
///     true residual, as the serial CG does. PETSc options with the prefix `solid_` (e.g.
///     -solid_ksp_monitor) override them.
/// The same Newton iterations as serial, to the solver's tolerance: every decision rests on
/// values that are the same on every rank.

#include <mpi.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/models/fem/solid_distribution.h"
#include "gipsi/parallel/mesh_partition.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable. Needs a ParallelSession for its whole lifetime.
class DistributedSolid final : public SolidDistribution {
 public:
  /// Collective: partitions `whole` (identical on every rank) over `comm`; keeps `whole` (the
  /// cavities of the solid are selected on it). Throws InputError (fewer tets than ranks),
  /// PetscError if PETSc fails.
  DistributedSolid(std::shared_ptr<const Mesh> whole, MPI_Comm comm);
  /// Collective: on a mesh already cut (`part`, this rank's, e.g. from PartitionMeshBlocks),
  /// which no rank holds whole: the part's boundary is found by exchanges (PartBoundary), and
  /// a cavity's faces are selected on the parts and gathered (SelectWholeFaces); there is no
  /// whole mesh (whole_mesh() aborts).
  DistributedSolid(MeshPart part, MPI_Comm comm);
  ~DistributedSolid() override;
  DistributedSolid(const DistributedSolid&) = delete;
  DistributedSolid& operator=(const DistributedSolid&) = delete;

  [[nodiscard]] const MeshPart& part() const { return part_; }
  [[nodiscard]] MPI_Comm comm() const { return comm_; }
  /// For each vertex of boundary(), its vertex in the whole mesh's boundary (MakeBoundary);
  /// for each face, its face there (whole_face()); with or without the whole mesh
  /// (NumberOnWholeBoundary).
  [[nodiscard]] const std::vector<int>& whole_boundary_vertex() const { return whole_vertex_; }
  [[nodiscard]] const std::vector<int>& whole_boundary_face() const { return whole_face_; }
  /// The whole mesh's boundary vertices and faces.
  [[nodiscard]] std::int64_t whole_boundary_vertices() const { return whole_vertices_; }
  [[nodiscard]] std::int64_t whole_boundary_faces() const { return whole_faces_; }

  [[nodiscard]] Index num_owned_nodes() const override { return part_.num_owned; }
  [[nodiscard]] const BoundarySurface& boundary() const override { return boundary_; }
  void Reduce(std::span<double> values, bool max) const override;
  void SumShared(VecX& v) const override;
  [[nodiscard]] std::unique_ptr<LinearSolver> MakeLinearSolver(const LinearSolverOptions& options,
                                                               const VecX& rest) const override;
  [[nodiscard]] std::int64_t WholeTetId(Index local) const override;
  [[nodiscard]] bool has_whole_mesh() const override { return whole_ != nullptr; }
  [[nodiscard]] WholeFaceSelection SelectWholeFaces(const Region& region) const override;
  [[nodiscard]] const Mesh& whole_mesh() const override;
  [[nodiscard]] const BoundarySurface& whole_boundary() const override;
  [[nodiscard]] std::span<const int> whole_face() const override { return whole_face_; }
  [[nodiscard]] std::span<const int> whole_node() const override { return part_.whole_node; }

 private:
  MPI_Comm comm_;
  std::shared_ptr<const Mesh> whole_;
  MeshPart part_;
  BoundarySurface boundary_, whole_boundary_;
  std::vector<int> whole_vertex_, whole_face_;
  std::int64_t whole_vertices_ = 0, whole_faces_ = 0;
  struct Ghosts;
  std::unique_ptr<Ghosts> ghosts_;  // SumShared's vector
};

}  // namespace gipsi
GIPSI_EXPORT_END
