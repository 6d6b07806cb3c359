/// @file
/// The transmural fibre rule's Laplace problem over the ranks.

#include "gipsi/parallel/distributed_fibres.h"

#include <fmt/format.h>
#include <petscksp.h>

#include <algorithm>
#include <array>
#include <limits>
#include <utility>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/numerics/p1_scalar.h"
#include "gipsi/parallel/petsc_check.h"
#include "gipsi/parallel/petsc_part.h"

namespace gipsi {
namespace {

// The PETSc objects of one solve, destroyed with it.
struct LaplaceSolve {
  Mat matrix = nullptr;
  Vec e = nullptr, rhs = nullptr;
  KSP ksp = nullptr;
  LaplaceSolve() = default;
  LaplaceSolve(const LaplaceSolve&) = delete;
  LaplaceSolve& operator=(const LaplaceSolve&) = delete;
  ~LaplaceSolve() {
    KSPDestroy(&ksp);
    VecDestroy(&rhs);
    VecDestroy(&e);
    MatDestroy(&matrix);
  }
};

}  // namespace

FibreField TransmuralFibresOnPart(const MeshPart& part, const TransmuralFibreRule& rule,
                                  MPI_Comm comm) {
  const Mesh& mesh = *part.mesh;
  const double tolerance = WholeRegionTolerance(part, comm);
  const std::vector<int> endo = SelectPartNodes(rule.endo, part, tolerance, comm);
  const std::vector<int> epi = SelectPartNodes(rule.epi, part, tolerance, comm);
  std::array<int, 2> found = {endo.empty() ? 0 : 1, epi.empty() ? 0 : 1};
  MPI_Allreduce(MPI_IN_PLACE, found.data(), 2, MPI_INT, MPI_MAX, comm);
  if (found[0] == 0) throw InputError("the fibre rule's endo region selects no node");
  if (found[1] == 0) throw InputError("the fibre rule's epi region selects no node");
  const auto n = static_cast<std::size_t>(part.num_local());
  std::vector<char> is_fixed(n, 0);
  std::vector<double> value(n, 0.0);
  for (const int i : endo) is_fixed[static_cast<std::size_t>(i)] = 1;
  int shared = std::numeric_limits<int>::max();  // the lowest whole node in both, as serially
  for (const int i : epi) {
    if (is_fixed[static_cast<std::size_t>(i)])
      shared = std::min(shared, part.whole_node[static_cast<std::size_t>(i)]);
    is_fixed[static_cast<std::size_t>(i)] = 1;
    value[static_cast<std::size_t>(i)] = 1.0;
  }
  MPI_Allreduce(MPI_IN_PLACE, &shared, 1, MPI_INT, MPI_MIN, comm);
  if (shared != std::numeric_limits<int>::max())
    throw InputError(fmt::format("node {} is in both the endo and the epi region", shared));

  LaplaceSolve s;
  {
    const P1ScalarOperators ops = AssembleP1Scalar(
        mesh.nodes, mesh.tets, 1.0, [](Index) -> Mat3 { return Mat3::Identity(); }, false);
    MakePartMatrix(part, ops.stiffness, comm, &s.matrix);
  }
  s.e = MakeGhostedNodeVec(part, comm);
  GIPSI_PETSC(VecDuplicate(s.e, &s.rhs));
  GIPSI_PETSC(VecSet(s.e, 0.0));
  GIPSI_PETSC(VecSet(s.rhs, 0.0));
  // The owned fixed nodes' rows and values: K_ff e_f = −K_fd e_d, the fixed rows the identity.
  std::vector<PetscInt> rows;
  std::vector<PetscScalar> values;
  for (std::size_t i = 0; i < static_cast<std::size_t>(part.num_owned); ++i)
    if (is_fixed[i]) {
      rows.push_back(static_cast<PetscInt>(part.global[i]));
      values.push_back(value[i]);
    }
  GIPSI_PETSC(VecSetValues(s.e, static_cast<PetscInt>(rows.size()), rows.data(), values.data(),
                           INSERT_VALUES));
  GIPSI_PETSC(VecAssemblyBegin(s.e));
  GIPSI_PETSC(VecAssemblyEnd(s.e));
  GIPSI_PETSC(MatZeroRowsColumns(s.matrix, static_cast<PetscInt>(rows.size()), rows.data(), 1.0,
                                 s.e, s.rhs));
  GIPSI_PETSC(KSPCreate(comm, &s.ksp));
  GIPSI_PETSC(KSPSetOptionsPrefix(s.ksp, "fibres_"));
  GIPSI_PETSC(KSPSetOperators(s.ksp, s.matrix, s.matrix));
  GIPSI_PETSC(KSPSetType(s.ksp, KSPCG));
  PC pc = nullptr;
  GIPSI_PETSC(KSPGetPC(s.ksp, &pc));
  GIPSI_PETSC(PCSetType(pc, PCJACOBI));
  GIPSI_PETSC(KSPSetNormType(s.ksp, KSP_NORM_UNPRECONDITIONED));
  GIPSI_PETSC(KSPSetTolerances(s.ksp, 1e-12, 1e-300, PETSC_DEFAULT, 100000));
  GIPSI_PETSC(KSPSetInitialGuessNonzero(s.ksp, PETSC_TRUE));  // the fixed values
  GIPSI_PETSC(KSPSetFromOptions(s.ksp));
  GIPSI_PETSC(KSPSolve(s.ksp, s.rhs, s.e));
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  PetscInt iterations = 0;
  GIPSI_PETSC(KSPGetConvergedReason(s.ksp, &reason));
  GIPSI_PETSC(KSPGetIterationNumber(s.ksp, &iterations));
  if (reason < 0)
    throw InputError(fmt::format(
        "the transmural Laplace problem could not be solved (is every part of the wall "
        "connected to the endocardium or the epicardium?): CG stopped after {} iterations ({})",
        iterations, KSPConvergedReasons[reason]));
  Log().debug("transmural fibre rule: Laplace solved by CG + Jacobi in {} iterations", iterations);
  GIPSI_PETSC(VecGhostUpdateBegin(s.e, INSERT_VALUES, SCATTER_FORWARD));
  GIPSI_PETSC(VecGhostUpdateEnd(s.e, INSERT_VALUES, SCATTER_FORWARD));
  VecX e(static_cast<Index>(n));
  Vec local = nullptr;
  const PetscScalar* array = nullptr;
  GIPSI_PETSC(VecGhostGetLocalForm(s.e, &local));
  GIPSI_PETSC(VecGetArrayRead(local, &array));
  std::copy(array, array + n, e.data());
  GIPSI_PETSC(VecRestoreArrayRead(local, &array));
  GIPSI_PETSC(VecGhostRestoreLocalForm(s.e, &local));
  // The fixed nodes take their values exactly, as in the serial solve (CG leaves them within
  // its tolerance), on every rank that holds them.
  for (std::size_t i = 0; i < n; ++i)
    if (is_fixed[i]) e[static_cast<Index>(i)] = value[i];
  return TransmuralFibresFrom(mesh, rule, std::move(e));
}

}  // namespace gipsi
