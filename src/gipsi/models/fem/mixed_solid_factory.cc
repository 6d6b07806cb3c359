/// @file
/// Scene-file factory of "MixedSolid" (its keys are documented in docs/scene-format.md).

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/models/fem/mixed_solid.h"
#include "gipsi/models/fem/solid_options.h"
#include "gipsi/models/fibres/rule_based_fibres.h"

namespace gipsi {

void RegisterMixedSolid(TypeRegistry& registry) {
  registry.objects.Register(
      "MixedSolid",
      [](const ObjectBuildContext& ctx) -> std::unique_ptr<SimObject> {
        const JsonNode& p = ctx.params;
        ctx.CheckKeys({"material", "formulation", "incompressible", "fibres", "load_steps",
                       "max_bisections", "newton", "linear_solver", "active_tension", "integrator",
                       "density", "damping", "gravity", "cavities", "predictor"});
        MixedSolidParams params;
        params.material = ctx.registry.CreateMaterialAs<SolidMaterial>(p.At("material"), "solid");
        if (auto formulation = p.Find("formulation"))
          static_cast<void>(formulation->AsChoice({"P2-P1"}));

        if (auto integrator = p.Find("integrator")) {
          const std::string kind =
              integrator->AsChoice({"Static", "BackwardEuler", "BDF2", "Newmark"});
          params.scheme = kind == "BackwardEuler" ? ImplicitSchemeKind::kBackwardEuler
                          : kind == "BDF2"        ? ImplicitSchemeKind::kBdf2
                          : kind == "Newmark"     ? ImplicitSchemeKind::kNewmark
                                                  : ImplicitSchemeKind::kStatic;
          if (params.scheme != ImplicitSchemeKind::kStatic && p.Has("load_steps"))
            p.At("load_steps")
                .Fail(
                    "has no effect with a dynamic integrator: a dynamic step is one solve at "
                    "the step's loads (make dt smaller instead)");
        }
        params.predictor = ParsePredictor(p, params.predictor);
        if (params.scheme == ImplicitSchemeKind::kStatic && p.Has("predictor"))
          p.At("predictor")
              .Fail(
                  "has no effect on a quasi-static MixedSolid (it predicts a dynamic step from "
                  "the velocities; set \"integrator\")");
        params.density = p.Positive("density", params.density);
        if (auto damping = p.Find("damping")) {
          damping->CheckKeys({"mass"});
          params.rayleigh_mass = damping->NonNegative("mass", 0);
        }
        params.gravity = p.Vector3("gravity", params.gravity);
        if (auto cavities = p.Find("cavities")) params.cavities = ParseCavitySpecs(*cavities);
        if (auto newton = p.Find("newton"))
          params.newton = ParseNewtonOptions(*newton, params.newton);
        params.incompressible = p.Bool("incompressible", params.incompressible);
        if (auto solver = p.Find("linear_solver")) {
          const double tolerance = params.linear_solver.tolerance;  // MixedSolid's default
          params.linear_solver = ParseLinearSolverOptions(*solver, /*saddle_point=*/true);
          if (!solver->Has("tolerance")) params.linear_solver.tolerance = tolerance;
          if (params.linear_solver.type == "cg" || params.linear_solver.type == "cholmod")
            solver->At("type").Expected(
                "\"umfpack\" or \"ldlt\": the mixed system is a saddle point, not positive "
                "definite (\"ldlt\" only when the material is not incompressible)");
          if (params.incompressible && params.linear_solver.type == "ldlt")
            solver->At("type").Expected(
                "\"umfpack\": an incompressible material's saddle point has a zero pressure "
                "block, which LDLT without pivoting cannot factorise");
        }
        ParseLoadStepping(p, params.load_steps, params.max_bisections);
        const SolidFibreRule fibre_rule =
            ParseSolidFibres(p, *params.material, params.fibre, params.sheet);
        if (params.material->log_volumetric_modulus() <= 0)
          p.At("material")
              .Fail(fmt::format(
                  "law '{}' has no volumetric term κ/2 (ln J)² for the mixed pressure to replace; "
                  "MixedSolid takes \"NeoHookean\" or \"Guccione\"",
                  params.material->law()));
        double active_tension = 0;
        if (auto active = p.Find("active_tension")) active_tension = active->AsNonNegative();
        try {
          auto mesh = ctx.DomainMesh();
          auto solid = std::make_unique<MixedSolid>(ctx.name, mesh, std::move(params));
          // A rule's fibres at each quadrature point: a 3 mm wall meshed with one or two tets
          // across still sees them turn. The Laplace rule's transmural coordinate is
          // interpolated there; the ellipsoidal rule is evaluated at the point itself.
          const TetQuadrature& rule = TetRuleDegree2();
          if (fibre_rule.transmural) {
            const FibreField fibres = MakeTransmuralFibres(*mesh, *fibre_rule.transmural);
            for (Index e = 0; e < mesh->num_tets(); ++e)
              for (int q = 0; q < 4; ++q) {
                double coordinate = 0;
                for (int b = 0; b < 4; ++b)
                  coordinate += rule.points[static_cast<std::size_t>(q)][b] *
                                fibres.transmural[mesh->tets(b, e)];
                solid->SetFibreAt(
                    e, q,
                    TransmuralFibreAt(*fibre_rule.transmural, fibres.sheet.col(e), coordinate));
              }
          }
          if (fibre_rule.ellipsoidal)
            for (Index e = 0; e < mesh->num_tets(); ++e)
              for (int q = 0; q < 4; ++q)
                solid->SetFibreAt(
                    e, q,
                    EllipsoidalFibreAt(*fibre_rule.ellipsoidal, solid->QuadraturePoint(e, q))
                        .fibre);
          if (active_tension > 0)
            solid->WriteField(solid->FindField("active_tension"),
                              Eigen::MatrixXd::Constant(1, mesh->num_tets(), active_tension));
          return solid;
        } catch (const InputError& e) {
          p.Fail(e.what());
        }
      },
      "nearly or fully incompressible solid on Taylor–Hood P2–P1 tetrahedra (locking-free), "
      "quasi-static or dynamic");
}

}  // namespace gipsi
