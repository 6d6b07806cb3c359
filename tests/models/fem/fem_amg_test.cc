// FemSolid with CG preconditioned by AMG or by symmetric block Gauss-Seidel ("sgs"), the
// benchmark's interactive set-up: the same steps as a direct solver, AMG iteration counts that
// stay bounded as the mesh is refined (FemSolid hands the solver its rigid-body modes), and
// Gauss-Seidel's far fewer iterations than Jacobi.

#include <memory>
#include <string>

#include <gtest/gtest.h>

#include "gipsi/geometry/generators.h"
#include "models/fem/fem_test_util.h"

namespace gipsi {
namespace {

/// The benchmark's set-up: a 0.1 m cube of cells³ hexahedra split into 5 tets each, x = 0 face
/// fixed, gravity, corotational E = 10 kPa, ν = 0.45, consistent mass, backward Euler with one
/// Newton iteration per step.
std::unique_ptr<FemSolid> SaggingCube(int cells, const LinearSolverOptions& solver) {
  auto mesh = std::make_shared<const Mesh>(
      MakeTetBox(Vec3::Zero(), Vec3(0.1, 0.1, 0.1), {cells, cells, cells}, HexSplit::kFive));
  FemParams params;
  params.material =
      testing::Law(R"({"law": "Corotational", "youngs_modulus": 1e4, "poisson_ratio": 0.45})");
  params.scheme = ImplicitSchemeKind::kBackwardEuler;
  params.newton.max_iterations = 1;
  params.newton.fixed_iterations = true;
  params.newton.line_search = false;
  params.linear_solver = solver;
  auto fem = std::make_unique<FemSolid>("cube", mesh, params);
  for (Index v : testing::VerticesWhere(*fem, [](const Vec3& p) { return p.x() == 0.0; }))
    fem->boundary_conditions().Fix(v);
  return fem;
}

// Five steps with CG + AMG to a relative residual of 1e-10 against the same steps with
// CHOLMOD. Each step's correction then differs by at most ~1e-10 κ(J) relative; J's condition
// number here is ~1e3 (stiffness over the mass term at dt = 10 ms, a 6-cell cube), so 1e-6 of
// the displacement bounds the difference with a wide margin, while a wrong preconditioner
// (CG not converging) or a wrong solution would miss it by orders of magnitude.
TEST(FemAmg, StepsMatchTheDirectSolver) {
  LinearSolverOptions direct{.type = "cholmod", .tolerance = 1e-10};
  for (const char* preconditioner : {"amg", "sgs"}) {
    LinearSolverOptions cg{.type = "cg", .preconditioner = preconditioner, .tolerance = 1e-10};
    auto a = SaggingCube(6, cg);
    auto b = SaggingCube(6, direct);
    for (int step = 0; step < 5; ++step) {
      ASSERT_TRUE(a->Step(0.01).ok()) << preconditioner;
      ASSERT_TRUE(b->Step(0.01).ok());
    }
    const VecX& ua = a->u();
    const VecX& ub = b->u();
    ASSERT_GT(ub.norm(), 0.0);
    EXPECT_LE((ua - ub).norm(), 1e-6 * ub.norm()) << preconditioner;
  }
}

// CG iterations per step at 1e-6 on the 9³-cell cube (3,645 tets, one Gauss-Seidel domain),
// four steps, warm-started as in the benchmark. Measured: Jacobi 80.25, sgs 31.5 per step (81 and
// 33 on the benchmark's 10³ cube). Half of Jacobi's leaves room for rounding; a preconditioner
// that is only block-diagonal saves ~7 % (measured on the benchmark tangent).
TEST(FemSgs, NeedsLessThanHalfTheIterationsOfJacobi) {
  double per_step[2] = {0.0, 0.0};
  const char* names[2] = {"jacobi", "sgs"};
  for (int k = 0; k < 2; ++k) {
    LinearSolverOptions cg{.type = "cg", .preconditioner = names[k], .tolerance = 1e-6};
    auto fem = SaggingCube(9, cg);
    for (int step = 0; step < 4; ++step) ASSERT_TRUE(fem->Step(0.01).ok()) << names[k];
    per_step[k] = static_cast<double>(fem->profile().linear_iterations) /
                  static_cast<double>(fem->profile().steps);
  }
  EXPECT_GT(per_step[1], 0.0);
  EXPECT_LT(2.0 * per_step[1], per_step[0]);
}

// CG iterations per step at 1e-6 as the cube is refined from 6³ to 12³ cells (1,080 to 8,640
// tets; 2 and 3 levels). Jacobi-CG needs ~1.7× more per doubling of the cells per side
// (84 at 10³ and 143 at 16³ in the benchmark); the multigrid counts grow slowly: measured
// 18.25, 19.5 and 21.25 per step here (22, 25, 29 at 10³, 16³, 25³ in the benchmark). The bound
// of 30 leaves slack for the lagged hierarchy, not for a count growing like Jacobi's.
TEST(FemAmg, CgIterationsStayBoundedUnderRefinement) {
  LinearSolverOptions amg{.type = "cg", .preconditioner = "amg", .tolerance = 1e-6};
  for (int cells : {6, 9, 12}) {
    auto fem = SaggingCube(cells, amg);
    for (int step = 0; step < 4; ++step) ASSERT_TRUE(fem->Step(0.01).ok()) << cells;
    const double per_step = static_cast<double>(fem->profile().linear_iterations) /
                            static_cast<double>(fem->profile().steps);
    EXPECT_LE(per_step, 30.0) << cells;
    EXPECT_GT(per_step, 0.0) << cells;
  }
}

}  // namespace
}  // namespace gipsi
