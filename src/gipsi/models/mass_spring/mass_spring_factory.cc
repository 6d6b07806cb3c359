/// @file
/// Scene-file factory of "MassSpring" (its keys are documented in docs/scene-format.md).

#include <optional>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/units.h"
#include "gipsi/geometry/quality.h"
#include "gipsi/geometry/region_json.h"
#include "gipsi/models/fibres/rule_based_fibres.h"
#include "gipsi/models/mass_spring/mass_spring.h"
#include "gipsi/models/mass_spring/mass_spring_local_model.h"

namespace gipsi {
namespace {

/// A MassSpring accepts a mesh with inverted tets (negative volume in node order 0-1-2-3), but
/// its volume preservation then pushes them further inside out: say so.
void WarnInvertedTets(const Mesh& mesh, const std::string& where) {
  Index inverted = 0, first = -1;
  for (Index e = 0; e < mesh.num_tets(); ++e) {
    const auto node = [&](int a) { return Vec3(mesh.nodes.col(mesh.tets(a, e))); };
    if (TetSignedVolume(node(0), node(1), node(2), node(3)) < 0) {
      if (inverted++ == 0) first = e;
    }
  }
  if (inverted > 0)
    Log().warn(
        "{}: {} of {} tets of the domain are inverted (negative volume in node order 0-1-2-3; "
        "the first is {}): volume preservation would push them further inside out; fix the "
        "mesh's node order (`gipsi info` lists them)",
        where, inverted, mesh.num_tets(), mesh.TetName(first));
}

}  // namespace

void RegisterMassSpring(TypeRegistry& registry) {
  LocalModels(registry).Register(
      "MassSpring",
      [](SimObject& object, int rings) -> std::unique_ptr<LocalModelBuilder> {
        return std::make_unique<MassSpringNeighbourhood>(dynamic_cast<MassSpring&>(object), rings);
      },
      "the springs within `rings` of the contact node, linearised (MassSpringNeighbourhood)");
  registry.objects.Register(
      "MassSpring",
      [](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        const JsonNode& p = ctx.params;
        ctx.CheckKeys({"density", "thickness", "stiffness", "damping", "drag", "gravity",
                       "max_stretch", "material", "volume_stiffness", "fibres", "cavities"});
        MassSpringParams params;
        params.density = p.Positive("density", params.density);
        params.thickness = p.Positive("thickness", params.thickness);
        params.stiffness = p.Positive("stiffness", params.stiffness);
        params.damping = p.NonNegative("damping", params.damping);
        params.drag = p.NonNegative("drag", params.drag);
        params.gravity = p.Vector3("gravity", params.gravity);
        params.max_stretch = p.Positive("max_stretch", params.max_stretch);
        if (auto k = p.Find("volume_stiffness")) params.volume_stiffness = k->AsNonNegative();
        if (auto material = p.Find("material"))
          params.law = ctx.registry.CreateMaterialAs<SpringLaw>(*material, "spring");
        std::optional<TransmuralFibreRule> fibre_rule;
        if (auto fibres = p.Find("fibres"); fibres && fibres->Has("rule")) {
          fibre_rule = ParseTransmuralFibreRule(*fibres);
        } else if (fibres) {
          fibres->CheckKeys({"direction"});
          params.fibre = fibres->Vector3("direction");
          if (params.fibre.norm() == 0) fibres->At("direction").Expected("a non-zero vector");
        }
        if (auto cavities = p.Find("cavities")) params.cavities = ParseCavitySpecs(*cavities);
        auto integrator = p.Has("integrator") ? ctx.registry.CreateIntegrator(p.At("integrator"))
                                              : std::make_unique<SymplecticEuler>();
        std::unique_ptr<MassSpring> object;
        try {
          auto mesh = ctx.DomainMesh();
          WarnInvertedTets(*mesh, p.file() + ": " + p.path());
          object = std::make_unique<MassSpring>(ctx.name, mesh, params, std::move(integrator));
          if (fibre_rule)
            object->WriteField(object->FindField("fibre"),
                               MakeTransmuralFibres(*mesh, *fibre_rule).fibre);
        } catch (const InputError& e) {
          p.Fail(e.what());
        }
        if (auto dt = p.Find("dt")) {
          const double value = ReadPositiveQuantity(*dt, "s");
          if (object->integrator().is_explicit() && value > object->stable_dt_estimate())
            Log().warn(
                "{}: {}: dt = {:.3g} s exceeds the estimated explicit stability limit {:.3g} s",
                dt->file(), dt->path(), value, object->stable_dt_estimate());
        }
        return object;
      },
      "mass-spring-damper tissue on the edges of a tet or triangle mesh, with optional fibre "
      "active tension and cavities");
}

}  // namespace gipsi
