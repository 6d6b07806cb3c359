/// @file
/// Scene-file factory of "FemSolid" (its keys are documented in docs/scene-format.md).

#include <algorithm>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/units.h"
#include "gipsi/geometry/region_json.h"
#include "gipsi/models/fem/fem_local_model.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/solid_options.h"
#include "gipsi/models/fibres/rule_based_fibres.h"

namespace gipsi {
namespace {

/// "integrator": one of FemSolid's implicit schemes (assembled tangent, Newton), or any other
/// integrator of the registry (RK4, SymplecticEuler, …), which steps the solid through the
/// OdeSystem contract (returned; the scheme is then unused).
std::unique_ptr<OdeIntegrator> ParseIntegrator(const JsonNode& node, const TypeRegistry& registry,
                                               ImplicitSchemeKind& scheme) {
  const std::string name = node.AsString();
  if (const auto kind = ImplicitSchemeNamed(name)) {
    scheme = *kind;
    return nullptr;
  }
  std::vector<std::string> known;
  for (const ImplicitSchemeKind kind : kImplicitSchemeKinds) known.emplace_back(ToString(kind));
  if (!registry.integrators.Contains(name)) {
    for (const std::string& other : registry.integrators.Names())
      if (std::find(known.begin(), known.end(), other) == known.end()) known.push_back(other);
    FailUnknown("integrator", name, known, node);
  }
  return registry.CreateIntegrator(node);
}

}  // namespace

NewtonOptions ParseNewtonOptions(const JsonNode& node, NewtonOptions options) {
  node.CheckKeys({"max_iterations", "tolerance", "absolute_tolerance", "increment_tolerance",
                  "relative_increment_tolerance", "line_search", "monotonicity_test",
                  "fixed_iterations", "reuse_factorization", "anderson"});
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
  if (auto it = node.Find("anderson")) {
    const std::int64_t m = it->AsInt();
    if (m < 0 || m > 8) it->Expected("an integer in [0, 8] (0: off)");
    options.anderson = static_cast<int>(m);
  }
  return options;
}

SolidFibreRule ParseSolidFibres(const JsonNode& object, const SolidMaterial& law, Vec3& fibre,
                                Vec3& sheet) {
  auto fibres = object.Find("fibres");
  if (fibres && fibres->Has("rule")) {
    if (fibres->At("rule").AsChoice({"transmural", "ellipsoidal"}) == "ellipsoidal")
      return {.transmural = std::nullopt, .ellipsoidal = ParseEllipsoidalFibreRule(*fibres)};
    return {.transmural = ParseTransmuralFibreRule(*fibres), .ellipsoidal = std::nullopt};
  }
  if (fibres) {
    fibres->CheckKeys({"direction", "sheet"});
    fibre = fibres->Vector3("direction");
    sheet = fibres->Vector3("sheet", sheet);
    if (fibre.norm() == 0) fibres->At("direction").Expected("a non-zero vector");
  } else if (law.needs_fibres()) {
    object.At("material")
        .Fail(fmt::format("law '{}' is anisotropic: give the object a fibre direction, e.g. "
                          "\"fibres\": {{\"direction\": [1, 0, 0]}}",
                          law.law()));
  }
  return {};
}

StepPredictor ParsePredictor(const JsonNode& object, StepPredictor fallback) {
  auto predictor = object.Find("predictor");
  if (!predictor) return fallback;
  const std::string choice =
      predictor->AsChoice({"none", "constant_velocity", "constant_acceleration"});
  return choice == "constant_velocity"       ? StepPredictor::kConstantVelocity
         : choice == "constant_acceleration" ? StepPredictor::kConstantAcceleration
                                             : StepPredictor::kNone;
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

FemSolidSpec ParseFemSolidSpec(const ObjectBuildContext& ctx) {
  const JsonNode& p = ctx.params;
  ctx.CheckKeys({"density", "material", "mass", "damping", "gravity", "newmark", "newton",
                 "linear_solver", "load_steps", "max_bisections", "predictor", "fibres", "cavities",
                 "parallel"});
  FemSolidSpec spec;
  FemParams& params = spec.params;
  std::unique_ptr<OdeIntegrator>& ode = spec.ode;
  SolidFibreRule& fibre_rule = spec.fibre_rule;
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
  if (auto integrator = p.Find("integrator"))
    ode = ParseIntegrator(*integrator, ctx.registry, params.scheme);
  if (ode) {
    if (!p.Has("mass")) params.lumped_mass = true;  // explicit dynamics' usual mass
    // Keys of the implicit schemes would silently do nothing: refuse them.
    for (const char* key :
         {"newmark", "newton", "linear_solver", "load_steps", "max_bisections", "predictor"})
      if (auto unused = p.Find(key))
        unused->Fail(
            fmt::format("has no effect with integrator '{}' (explicit dynamics through the ODE "
                        "contract); remove it, or choose an implicit scheme (\"BackwardEuler\", "
                        "\"BDF2\", \"Newmark\", \"Static\")",
                        ode->name()));
  }
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
  if (auto newton = p.Find("newton")) params.newton = ParseNewtonOptions(*newton, params.newton);
  if (auto solver = p.Find("linear_solver"))
    params.linear_solver = ParseLinearSolverOptions(*solver);
  ParseLoadStepping(p, params.load_steps, params.max_bisections);
  params.predictor = ParsePredictor(p, params.predictor);
  fibre_rule = ParseSolidFibres(p, *params.material, params.fibre, params.sheet);
  if (auto cavities = p.Find("cavities")) params.cavities = ParseCavitySpecs(*cavities);
  // The solver of distributed runs: linear_solver's, with the "parallel" block's keys over it
  // (PETSc's: "amg" is GAMG, "hypre" BoomerAMG, the direct types MUMPS); CG without a
  // preconditioner named anywhere takes GAMG (docs/scale-out.md). Checked in every run.
  LinearSolverOptions distributed = params.linear_solver;
  bool preconditioner_given = false;
  if (auto solver = p.Find("linear_solver")) preconditioner_given = solver->Has("preconditioner");
  if (auto parallel = p.Find("parallel")) {
    parallel->CheckKeys({"linear_solver"});
    const JsonNode solver = parallel->At("linear_solver");
    solver.CheckKeys({"type", "preconditioner", "tolerance", "max_iterations"});
    if (auto type = solver.Find("type"))
      distributed.type = type->AsChoice({"cg", "cholmod", "ldlt", "umfpack"});
    if (auto preconditioner = solver.Find("preconditioner")) {
      distributed.preconditioner =
          preconditioner->AsChoice({"none", "jacobi", "sgs", "amg", "hypre"});
      preconditioner_given = true;
    }
    distributed.tolerance = solver.Positive("tolerance", distributed.tolerance);
    if (auto max_iterations = solver.Find("max_iterations")) {
      const std::int64_t n = max_iterations->AsInt();
      if (n < 1 || n > 1000000) max_iterations->Expected("a number of iterations in [1, 1000000]");
      distributed.max_iterations = static_cast<int>(n);
    }
  }
  if (distributed.type == "cg" && !preconditioner_given) distributed.preconditioner = "amg";
  spec.distributed_linear = distributed;
  return spec;
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
        FemSolidSpec spec = ParseFemSolidSpec(ctx);
        FemParams& params = spec.params;
        std::unique_ptr<OdeIntegrator>& ode = spec.ode;
        const SolidFibreRule& fibre_rule = spec.fibre_rule;
        std::unique_ptr<FemSolid> solid;
        try {
          auto mesh = ctx.DomainMesh();
          solid =
              ode ? std::make_unique<FemSolid>(ctx.name, mesh, std::move(params), std::move(ode))
                  : std::make_unique<FemSolid>(ctx.name, mesh, std::move(params));
          if (fibre_rule.transmural)
            solid->WriteField(solid->FindField("fibre"),
                              MakeTransmuralFibres(*mesh, *fibre_rule.transmural).fibre);
          if (fibre_rule.ellipsoidal)
            solid->WriteField(solid->FindField("fibre"),
                              EllipsoidalFibresAtCentroids(*mesh, *fibre_rule.ellipsoidal));
        } catch (const InputError& e) {
          p.Fail(e.what());
        }
        if (auto dt = p.Find("dt");
            dt && solid->ode_integrator() && solid->ode_integrator()->is_explicit()) {
          const double value = ReadPositiveQuantity(*dt, "s");
          const double limit = solid->stable_dt_estimate();
          if (value > limit)
            Log().warn(
                "{}: {}: dt = {:.3g} s exceeds the estimated explicit stability limit {:.3g} s",
                dt->file(), dt->path(), value, limit);
        }
        return solid;
      },
      "nonlinear solid mechanics on P1 tetrahedra with implicit time stepping, or explicit through "
      "the ODE contract");
}

}  // namespace gipsi
