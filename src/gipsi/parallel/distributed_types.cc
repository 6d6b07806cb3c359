/// @file
/// Factories of the distributed object types.

#include "gipsi/parallel/distributed_types.h"

#include "gipsi/base/error.h"
#include "gipsi/models/ep/ep_tissue_json.h"
#include "gipsi/parallel/distributed_monodomain.h"
#include "gipsi/parallel/whole_domain_view.h"

namespace gipsi {

void RegisterDistributedTypes(TypeRegistry& registry, MPI_Comm comm) {
  registry.objects.Replace(
      "Monodomain", [comm](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        CheckEpTissueKeys(ctx, {"parallel"});
        EpTissueParams params = ParseEpTissueParams(ctx);
        std::shared_ptr<const Mesh> whole = ctx.DomainMesh();
        try {
          auto part =
              std::make_unique<DistributedMonodomain>(ctx.name, *whole, std::move(params), comm);
          const MeshPart& mesh_part = part->part();
          return std::make_unique<WholeDomainView>(std::move(part), mesh_part, whole, comm);
        } catch (const InputError& e) {
          ctx.params.Fail(e.what());
        }
      });
}

std::vector<std::string> DistributedTypeNames() { return {"Monodomain"}; }

}  // namespace gipsi
