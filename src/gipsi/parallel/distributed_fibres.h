#pragma once
/// @file
/// The transmural fibre rule (models/fibres/rule_based_fibres.h) on a split mesh: its Laplace
/// problem solved over the ranks, so that no rank needs the whole mesh.

#include <mpi.h>

#include "gipsi/base/export.h"
#include "gipsi/models/fibres/rule_based_fibres.h"
#include "gipsi/parallel/mesh_partition.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// MakeTransmuralFibres of the whole mesh, restricted to this rank's part: e at the part's
/// nodes and the fibre and sheet of its tets. The endo and epi regions are selected on the parts
/// as the whole mesh would select them (SelectPartNodes); the P1 Laplace matrix is assembled on
/// each rank's tets into one PETSc matrix, the Dirichlet values are imposed by symmetric
/// elimination (MatZeroRowsColumns), and CG with Jacobi solves it to a relative residual of
/// 1e-12 (PETSc options prefix `fibres_`). Jacobi, not a multigrid: its iterations are the same
/// in every run on a rank count (GAMG's are not on more than 2 ranks, docs/scale-out.md), and
/// the wall's Dirichlet surfaces keep the problem well conditioned (its iterations grow with the
/// wall's thickness in elements, not with the mesh). e agrees with the serial direct solve to
/// about the solve's tolerance times the condition number. Throws InputError on every rank
/// alike with MakeTransmuralFibres's messages, and when CG does not converge. Collective.
FibreField TransmuralFibresOnPart(const MeshPart& part, const TransmuralFibreRule& rule,
                                  MPI_Comm comm);

}  // namespace gipsi
GIPSI_EXPORT_END
