/// @file
/// Scene-file factory of "FemSolid" (its keys are documented in docs/scene-format.md).

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/region_json.h"
#include "gipsi/models/fem/fem_local_model.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/solid_options.h"
#include "gipsi/models/fibres/rule_based_fibres.h"

namespace gipsi {
namespace {

ImplicitSchemeKind ParseScheme(const JsonNode& node) {
  const std::string name = node.AsChoice({"Static", "BackwardEuler", "BDF2", "Newmark"});
  if (name == "Static") return ImplicitSchemeKind::kStatic;
  if (name == "BDF2") return ImplicitSchemeKind::kBdf2;
  if (name == "Newmark") return ImplicitSchemeKind::kNewmark;
  return ImplicitSchemeKind::kBackwardEuler;
}

}  // namespace

NewtonOptions ParseNewtonOptions(const JsonNode& node, NewtonOptions options) {
  node.CheckKeys({"max_iterations", "tolerance", "absolute_tolerance", "increment_tolerance",
                  "relative_increment_tolerance", "line_search", "monotonicity_test",
                  "fixed_iterations", "reuse_factorization"});
  if (auto it = node.Find("max_iterations")) {
    const std::int64_t n = it->AsInt();
    if (n < 1 || n > 10000) it->Expected("an integer in [1, 10000]");
    options.max_iterations = static_cast<int>(n);
  }
  options.tolerance = node.Positive("tolerance", options.tolerance);
  options.absolute_tolerance = node.NonNegative("absolute_tolerance", options.absolute_tolerance);
  options.increment_tolerance =
      node.NonNegative("increment_tolerance", options.increment_tolerance);
  options.relative_increment_tolerance =
      node.NonNegative("relative_increment_tolerance", options.relative_increment_tolerance);
  options.line_search = node.Bool("line_search", options.line_search);
  options.monotonicity_test = node.Bool("monotonicity_test", options.monotonicity_test);
  options.fixed_iterations = node.Bool("fixed_iterations", options.fixed_iterations);
  options.reuse_factorization = node.Bool("reuse_factorization", options.reuse_factorization);
  return options;
}

void ParseLoadStepping(const JsonNode& object, int& load_steps, int& max_bisections) {
  if (auto steps = object.Find("load_steps")) {
    const std::int64_t n = steps->AsInt();
    if (n < 1 || n > 100000) steps->Expected("an integer in [1, 100000]");
    load_steps = static_cast<int>(n);
  }
  if (auto bisections = object.Find("max_bisections")) {
    const std::int64_t n = bisections->AsInt();
    if (n < 0 || n > 30) bisections->Expected("an integer in [0, 30]");
    max_bisections = static_cast<int>(n);
  }
}

void RegisterFemSolid(TypeRegistry& registry) {
  LocalModels(registry).Register(
      "FemSolid",
      [](SimObject& object, int /*rings*/) -> std::unique_ptr<LocalModelBuilder> {
        return std::make_unique<FemCondensation>(dynamic_cast<FemSolid&>(object));
      },
      "the tangent stiffness condensed at the contact node (FemCondensation)");
  registry.objects.Register(
      "FemSolid",
      [](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        const JsonNode& p = ctx.params;
        ctx.CheckKeys({"density", "material", "mass", "damping", "gravity", "newmark", "newton",
                       "linear_solver", "load_steps", "max_bisections", "predictor", "fibres",
                       "cavities"});
        FemParams params;
        params.density = p.Positive("density", params.density);
        params.material = ctx.registry.CreateMaterialAs<SolidMaterial>(p.At("material"), "solid");
        if (auto mass = p.Find("mass"))
          params.lumped_mass = mass->AsChoice({"lumped", "consistent"}) == "lumped";
        if (auto damping = p.Find("damping")) {
          damping->CheckKeys({"mass", "stiffness"});
          params.rayleigh_mass = damping->NonNegative("mass", 0);
          params.rayleigh_stiffness = damping->NonNegative("stiffness", 0);
        }
        params.gravity = p.Vector3("gravity", params.gravity);
        if (auto integrator = p.Find("integrator")) params.scheme = ParseScheme(*integrator);
        if (auto newmark = p.Find("newmark")) {
          newmark->CheckKeys({"beta", "gamma"});
          params.newmark_beta = newmark->Positive("beta", params.newmark_beta);
          params.newmark_gamma = newmark->Positive("gamma", params.newmark_gamma);
          if (params.newmark_gamma < 0.5 || params.newmark_beta < 0.25 * params.newmark_gamma)
            newmark->Fail(fmt::format(
                "beta = {} and gamma = {} are not unconditionally stable; use gamma >= 1/2 and "
                "beta >= gamma/4 (average acceleration: beta 0.25, gamma 0.5)",
                params.newmark_beta, params.newmark_gamma));
        }
        if (auto newton = p.Find("newton"))
          params.newton = ParseNewtonOptions(*newton, params.newton);
        if (auto solver = p.Find("linear_solver"))
          params.linear_solver = ParseLinearSolverOptions(*solver);
        ParseLoadStepping(p, params.load_steps, params.max_bisections);
        if (auto predictor = p.Find("predictor"))
          params.predict_velocity =
              predictor->AsChoice({"none", "constant_velocity"}) == "constant_velocity";
        std::optional<TransmuralFibreRule> fibre_rule;
        if (auto fibres = p.Find("fibres"); fibres && fibres->Has("rule")) {
          fibre_rule = ParseTransmuralFibreRule(*fibres);
        } else if (fibres) {
          fibres->CheckKeys({"direction", "sheet"});
          params.fibre = fibres->Vector3("direction");
          params.sheet = fibres->Vector3("sheet", params.sheet);
          if (params.fibre.norm() == 0) fibres->At("direction").Expected("a non-zero vector");
        } else if (params.material->needs_fibres()) {
          p.At("material")
              .Fail(fmt::format(
                  "law '{}' is anisotropic: give the object a fibre field, e.g. \"fibres\": "
                  "{{\"direction\": [1, 0, 0]}}",
                  params.material->law()));
        }
        if (auto cavities = p.Find("cavities")) params.cavities = ParseCavitySpecs(*cavities);
        try {
          auto mesh = ctx.DomainMesh();
          auto solid = std::make_unique<FemSolid>(ctx.name, mesh, std::move(params));
          if (fibre_rule)
            solid->WriteField(solid->FindField("fibre"),
                              MakeTransmuralFibres(*mesh, *fibre_rule).fibre);
          return solid;
        } catch (const InputError& e) {
          p.Fail(e.what());
        }
      },
      "nonlinear solid mechanics on P1 tetrahedra with implicit time stepping");
}

}  // namespace gipsi
