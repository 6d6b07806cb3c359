#pragma once
/// @file
/// PETSc objects over a part's nodes (parallel/mesh_partition.h), for the parallel layer's own
/// sources (not installed API).

#include <mpi.h>
#include <petscmat.h>

#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/parallel/mesh_partition.h"

namespace gipsi {

/// `local`, a matrix over the part's local nodes (assembled on its tets), as one PETSc AIJ
/// matrix over the ranks in the global numbering (MeshPart::global): given by its COO entries,
/// those of shared nodes summed over the ranks. Destroys `*out` first. Collective.
void MakePartMatrix(const MeshPart& part, const SparseMatrix& local, MPI_Comm comm, Mat* out);

/// A ghosted vector of one value per node of the part: its owned nodes, then the shared ones,
/// in local order (VecGhostGetLocalForm). Collective.
Vec MakeGhostedNodeVec(const MeshPart& part, MPI_Comm comm);

}  // namespace gipsi
