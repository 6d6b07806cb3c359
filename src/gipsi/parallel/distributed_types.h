#pragma once
/// @file
/// The object types a distributed scene run splits over the ranks (`mpirun -np N gipsi run
/// SCENE`, docs/scale-out.md). Today: "Monodomain" (a DistributedMonodomain behind a
/// WholeDomainView) and "FemSolid" (a FemSolid on each rank's part with a DistributedSolid,
/// behind a WholeDomainView, cavities included; one with the ODE contract's implicit integrator
/// or a plugin's integrator still runs whole). Every other object of the scene runs whole on
/// every rank, each rank computing the same steps, so connectors, events and outputs see the same
/// values everywhere.

#include <mpi.h>

#include <memory>
#include <string>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/core/registry.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Replaces the factories of the types that run distributed over `comm` in `registry` (after
/// RegisterBuiltins). Their scene keys are the serial types' own. Each object they split is
/// added to `split` (if given) as "name (Type)".
void RegisterDistributedTypes(TypeRegistry& registry, MPI_Comm comm,
                              std::shared_ptr<std::vector<std::string>> split = nullptr);

}  // namespace gipsi
GIPSI_EXPORT_END
