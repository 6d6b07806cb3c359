/// @file
/// PETSc objects over a part's nodes.

#include "gipsi/parallel/petsc_part.h"

#include <vector>

#include "gipsi/parallel/petsc_check.h"

namespace gipsi {

void MakePartMatrix(const MeshPart& part, const SparseMatrix& local, MPI_Comm comm, Mat* out) {
  const auto entries = static_cast<std::size_t>(local.nonZeros());
  std::vector<PetscInt> rows(entries), cols(entries);
  for (Index j = 0; j < local.outerSize(); ++j)
    for (int at = local.outerIndexPtr()[j]; at < local.outerIndexPtr()[j + 1]; ++at) {
      rows[static_cast<std::size_t>(at)] =
          static_cast<PetscInt>(part.global[static_cast<std::size_t>(local.innerIndexPtr()[at])]);
      cols[static_cast<std::size_t>(at)] =
          static_cast<PetscInt>(part.global[static_cast<std::size_t>(j)]);
    }
  const auto owned = static_cast<PetscInt>(part.num_owned);
  const auto global = static_cast<PetscInt>(part.num_global_nodes);
  GIPSI_PETSC(MatDestroy(out));
  GIPSI_PETSC(MatCreate(comm, out));
  GIPSI_PETSC(MatSetSizes(*out, owned, owned, global, global));
  GIPSI_PETSC(MatSetType(*out, MATAIJ));
  GIPSI_PETSC(
      MatSetPreallocationCOO(*out, static_cast<PetscCount>(entries), rows.data(), cols.data()));
  GIPSI_PETSC(MatSetValuesCOO(*out, local.valuePtr(), INSERT_VALUES));
}

Vec MakeGhostedNodeVec(const MeshPart& part, MPI_Comm comm) {
  std::vector<PetscInt> ghosts;
  for (std::size_t i = static_cast<std::size_t>(part.num_owned); i < part.global.size(); ++i)
    ghosts.push_back(static_cast<PetscInt>(part.global[i]));
  Vec v = nullptr;
  GIPSI_PETSC(VecCreateGhost(comm, static_cast<PetscInt>(part.num_owned),
                             static_cast<PetscInt>(part.num_global_nodes),
                             static_cast<PetscInt>(ghosts.size()), ghosts.data(), &v));
  return v;
}

}  // namespace gipsi
