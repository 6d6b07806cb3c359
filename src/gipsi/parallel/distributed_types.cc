/// @file
/// Factories of the distributed object types.

#include "gipsi/parallel/distributed_types.h"

#include <fmt/format.h>

#include <functional>
#include <string>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/units.h"
#include "gipsi/models/ep/ep_tissue_json.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/numerics/implicit_scheme.h"
#include "gipsi/parallel/distributed_fibres.h"
#include "gipsi/parallel/distributed_monodomain.h"
#include "gipsi/parallel/distributed_solid.h"
#include "gipsi/parallel/whole_domain_view.h"

namespace gipsi {

namespace {

// Warns when an explicit integrator's dt exceeds the stability estimate (collective).
void CheckExplicitDt(const ObjectBuildContext& ctx, const FemSolid& solid) {
  if (auto dt = ctx.params.Find("dt"); dt && solid.ode_integrator()) {
    const double value = ReadPositiveQuantity(*dt, "s");
    const double limit = solid.stable_dt_estimate();  // collective
    if (value > limit)
      Log().warn("{}: {}: dt = {:.3g} s exceeds the estimated explicit stability limit {:.3g} s",
                 dt->file(), dt->path(), value, limit);
  }
}

// Writes a scene's fibre rule into a split solid's "fibre" field (its part's tets): an
// ellipsoidal rule evaluated on the local tets alone, a transmural one solved over the ranks.
void WriteFibreRule(FemSolid& solid, const MeshPart& part, const SolidFibreRule& rule,
                    MPI_Comm comm) {
  if (rule.ellipsoidal)
    solid.WriteField(solid.FindField("fibre"),
                     EllipsoidalFibresAtCentroids(*part.mesh, *rule.ellipsoidal));
  if (rule.transmural)
    solid.WriteField(solid.FindField("fibre"),
                     TransmuralFibresOnPart(part, *rule.transmural, comm).fibre);
}

// The FemSolid on `distribution`'s part, with the scene's integrator (taken from `spec`) and
// fibre rule, its explicit dt checked (collective).
std::unique_ptr<FemSolid> MakePartSolid(const ObjectBuildContext& ctx, FemSolidSpec& spec,
                                        std::shared_ptr<DistributedSolid> distribution,
                                        MPI_Comm comm) {
  const MeshPart& part = distribution->part();
  spec.params.distribution = std::move(distribution);
  auto solid = spec.ode ? std::make_unique<FemSolid>(ctx.name, part.mesh, std::move(spec.params),
                                                     std::move(spec.ode))
                        : std::make_unique<FemSolid>(ctx.name, part.mesh, std::move(spec.params));
  WriteFibreRule(*solid, part, spec.fibre_rule, comm);
  CheckExplicitDt(ctx, *solid);
  return solid;
}

// Whether an object's JSON embeds a display mesh (which needs the whole domain mesh).
bool HasDisplayMesh(const JsonNode& params) {
  const auto display = params.Find("display");
  return display && display->is_object() && display->Has("mesh");
}

// The integrators a split FemSolid steps with: FemSolid's own implicit schemes (whose names
// take precedence over the ODE contract's "BackwardEuler") and the fixed-step explicit ones of
// the ODE contract. A plugin's, which might adapt its steps from a norm of the state that would
// differ between ranks, runs whole on every rank, as every object did before.
bool SplitsWithIntegrator(const JsonNode& params) {
  const auto integrator = params.Find("integrator");
  if (!integrator) return true;
  if (!integrator->is_string()) return false;  // refused by the serial factory
  const std::string name = integrator->AsString();
  return ImplicitSchemeNamed(name) || name == "RK4" || name == "SymplecticEuler" ||
         name == "ExplicitEuler";
}

// Adds an object to the summary's list of split objects.
using NoteSplit = std::function<void(const std::string& name, const char* type)>;

// The cuts of the meshes made in blocks, one per mesh of a scene: the objects made in blocks on
// one mesh (the heart's bioelectricity and muscle) read its blocks and run the partitioner once,
// and share the part's mesh (each keeps its own copy of the part's index arrays). The cut is
// deterministic, so this changes no result; it spares a second read of the file and a second
// partitioning. A mesh is known by its name in the scene and by the scene's document: the entry
// keeps a node of that document, whose file name string (shared by all its nodes) then stays
// alive, so its address names that load alone, even after the scene is gone and another is
// loaded with the same registry. Every rank makes the same calls in the same order (collective).
class SharedCuts {
 public:
  // The part of this rank of the object's domain mesh: cut now, or as an earlier object's. A
  // mistake in the mesh names its own JSON path; one the cut meets (no tets, fewer tets than
  // ranks), the object's.
  MeshPart Cut(const ObjectBuildContext& ctx, MPI_Comm comm, const char* type) {
    const JsonNode domain = ctx.params.At("domain");
    const std::string name = domain.AsString();
    for (const Entry& entry : entries_)
      if (&entry.document.file() == &domain.file() && entry.mesh == name) return *entry.part;
    int rank = 0, size = 1;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    auto block = std::make_unique<MeshBlock>(ctx.DomainMeshBlock(rank, size));
    if (block->num_tets == 0)
      ctx.params.Fail(
          fmt::format("the {} object needs a tetrahedral domain mesh (this one has none)", type));
    std::shared_ptr<const MeshPart> part;
    try {
      part = std::make_shared<const MeshPart>(PartitionMeshBlocks(*block, comm));
    } catch (const InputError& e) {
      ctx.params.Fail(e.what());
    }
    entries_.push_back({domain, name, part});
    return *part;  // the block goes before the object allocates its state
  }

 private:
  struct Entry {
    JsonNode document;  // a node of the scene's document: keeps its file name string alive
    std::string mesh;
    std::shared_ptr<const MeshPart> part;
  };
  std::vector<Entry> entries_;
};

// A FemSolid made in blocks (ObjectBuildContext::in_blocks): on a mesh made as one block per rank
// and cut from the blocks: its boundary and where it lies on the whole mesh's are found by
// exchanges, its cavities' faces are selected on the parts and gathered, and the view keeps the
// scene's conditions on the whole boundary's numbering without its geometry.

std::unique_ptr<SimObject> FemSolidInBlocks(const ObjectBuildContext& ctx, FemSolidSpec spec,
                                            MeshPart cut, MPI_Comm comm, const NoteSplit& note) {
  auto distribution = std::make_shared<DistributedSolid>(std::move(cut), comm);
  const MeshPart& mesh_part = distribution->part();
  std::unique_ptr<FemSolid> solid = MakePartSolid(ctx, spec, distribution, comm);
  note(ctx.name, "FemSolid, in blocks");
  return std::make_unique<WholeDomainView>(
      std::move(solid), mesh_part, comm,
      WholeDomainView::BoundaryMap{
          distribution->whole_boundary_vertex(), distribution->whole_boundary_face(),
          distribution->whole_boundary_vertices(), distribution->whole_boundary_faces()});
}

}  // namespace

void RegisterDistributedTypes(TypeRegistry& registry, MPI_Comm comm,
                              std::shared_ptr<std::vector<std::string>> split) {
  auto note = [split](const std::string& name, const char* type) {
    if (split) split->push_back(fmt::format("{} ({})", name, type));
  };
  registry.meshes_in_blocks = true;
  // Made in blocks when the scene lets them be (ObjectBuildContext::in_blocks): a Monodomain
  // unless boundary conditions or an embedded display need its whole mesh, a FemSolid unless an
  // embedded display does or its integrator runs whole.
  registry.splits_in_blocks["Monodomain"] = [](const JsonNode& params) {
    return !params.Has("boundary_conditions") && !HasDisplayMesh(params);
  };
  registry.splits_in_blocks["FemSolid"] = [](const JsonNode& params) {
    return !HasDisplayMesh(params) && SplitsWithIntegrator(params);
  };
  // Aggregates whose own code reads only their parts' global fields (the heart's monitor reads
  // its blood's): made in blocks, they make their parts so by the same rule among the parts.
  for (const char* aggregate : {"Aggregate", "Heart"})
    registry.splits_in_blocks[aggregate] = [](const JsonNode&) { return true; };
  // One cut per mesh made in blocks, shared by the objects on it (the factories' own).
  auto cuts = std::make_shared<SharedCuts>();
  registry.objects.Replace(
      "Monodomain",
      [comm, note, cuts](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        CheckEpTissueKeys(ctx, {"parallel"});
        EpTissueParams params = ParseEpTissueParams(ctx);
        // Nothing but probes, outputs and connectors coupling its parts reads it: its mesh is
        // made in blocks and no rank holds it whole.
        if (ctx.in_blocks) {
          MeshPart cut = cuts->Cut(ctx, comm, "Monodomain");
          try {
            auto part = std::make_unique<DistributedMonodomain>(ctx.name, std::move(cut),
                                                                std::move(params), comm);
            const MeshPart& mesh_part = part->part();
            note(ctx.name, "Monodomain, in blocks");
            return std::make_unique<WholeDomainView>(std::move(part), mesh_part, comm);
          } catch (const InputError& e) {
            ctx.params.Fail(e.what());
          }
        }
        std::shared_ptr<const Mesh> whole = ctx.DomainMesh();
        try {
          auto part =
              std::make_unique<DistributedMonodomain>(ctx.name, *whole, std::move(params), comm);
          const MeshPart& mesh_part = part->part();
          note(ctx.name, "Monodomain");
          return std::make_unique<WholeDomainView>(std::move(part), mesh_part, whole, comm);
        } catch (const InputError& e) {
          ctx.params.Fail(e.what());
        }
      });
  // A FemSolid whose integrator runs whole (SplitsWithIntegrator) is the serial one.
  const ObjectFactory* found = registry.objects.Find("FemSolid");
  GIPSI_CHECK(found != nullptr);
  registry.objects.Replace(
      "FemSolid",
      [comm, note, cuts,
       whole_solid = *found](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        if (!SplitsWithIntegrator(ctx.params)) return whole_solid(ctx);
        FemSolidSpec spec = ParseFemSolidSpec(ctx);
        spec.params.linear_solver = spec.distributed_linear;
        // Nothing but probes, outputs and connectors coupling its parts reads it: its mesh is
        // made in blocks and no rank holds it whole.
        if (ctx.in_blocks) {
          MeshPart cut = cuts->Cut(ctx, comm, "FemSolid");
          try {
            return FemSolidInBlocks(ctx, std::move(spec), std::move(cut), comm, note);
          } catch (const InputError& e) {
            ctx.params.Fail(e.what());
          }
        }
        std::shared_ptr<const Mesh> whole = ctx.DomainMesh();
        try {
          auto distribution = std::make_shared<DistributedSolid>(whole, comm);
          const MeshPart& mesh_part = distribution->part();
          std::unique_ptr<FemSolid> solid = MakePartSolid(ctx, spec, distribution, comm);
          note(ctx.name, "FemSolid");
          return std::make_unique<WholeDomainView>(
              std::move(solid), mesh_part, whole, comm,
              WholeDomainView::BoundaryMap{distribution->whole_boundary_vertex(),
                                           distribution->whole_boundary_face()});
        } catch (const InputError& e) {
          ctx.params.Fail(e.what());
        }
      });
}

}  // namespace gipsi
