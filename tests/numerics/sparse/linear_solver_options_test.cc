// Reading LinearSolverOptions from JSON, and MakeLinearSolver's validation: errors name the
// file and JSON path and list the choices.

#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/base/json_node.h"
#include "gipsi/numerics/sparse/linear_solver.h"

namespace gipsi {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

/// Parses `{"solver": <solver_json>}` from "scene.json" and reads its "solver" member.
LinearSolverOptions Parse(const std::string& solver_json) {
  const JsonDocument doc = JsonDocument::Parse("{\"solver\": " + solver_json + "}", "scene.json");
  return ParseLinearSolverOptions(doc.root().At("solver"));
}

TEST(LinearSolverOptions, EmptyObjectGivesTheDefaults) {
  const LinearSolverOptions options = Parse("{}");
  const LinearSolverOptions defaults;
  EXPECT_EQ(options.type, defaults.type);
  EXPECT_EQ(options.preconditioner, defaults.preconditioner);
  EXPECT_EQ(options.tolerance, defaults.tolerance);
  EXPECT_EQ(options.max_iterations, defaults.max_iterations);
  EXPECT_EQ(options.refactor_iterations, defaults.refactor_iterations);
}

TEST(LinearSolverOptions, ReadsEveryKey) {
  const LinearSolverOptions options =
      Parse(R"({"type": "cg", "preconditioner": "cholesky", "tolerance": 1e-8,
                "max_iterations": 50, "refactor_iterations": 7})");
  EXPECT_EQ(options.type, "cg");
  EXPECT_EQ(options.preconditioner, "cholesky");
  EXPECT_EQ(options.tolerance, 1e-8);
  EXPECT_EQ(options.max_iterations, 50);
  EXPECT_EQ(options.refactor_iterations, 7);
  EXPECT_EQ(Parse(R"({"type": "cholmod"})").type, "cholmod");
}

TEST(LinearSolverOptions, UnknownTypeNamesPathAndListsChoices) {
  EXPECT_THAT([] { Parse(R"({"type": "gmres"})"); },
              ThrowsMessage<InputError>(
                  AllOf(HasSubstr("scene.json: solver.type: unknown linear solver type 'gmres'"),
                        HasSubstr("'cg', 'ldlt', 'cholmod'"))));
  EXPECT_THAT([] { Parse(R"({"type": 3})"); },
              ThrowsMessage<InputError>(HasSubstr("scene.json: solver.type: expected a string")));
}

// "schur_gmres" needs a saddle point's blocks: only MixedSolid asks for it; any other object
// gets the key's path and why.
TEST(LinearSolverOptions, SchurGmresIsForSaddlePointsOnly) {
  EXPECT_THAT([] { Parse(R"({"type": "schur_gmres"})"); },
              ThrowsMessage<InputError>(HasSubstr(
                  "scene.json: solver.type: 'schur_gmres' solves the saddle points of mixed "
                  "elements (a MixedSolid's); this object's systems are not saddle points")));
  const JsonDocument doc =
      JsonDocument::Parse(R"({"solver": {"type": "schur_gmres"}})", "scene.json");
  EXPECT_EQ(ParseLinearSolverOptions(doc.root().At("solver"), true).type, "schur_gmres");
}

TEST(LinearSolverOptions, UnknownPreconditionerNamesPathSuggestsAndListsChoices) {
  EXPECT_THAT([] { Parse(R"({"preconditioner": "jacoby"})"); },
              ThrowsMessage<InputError>(
                  AllOf(HasSubstr("solver.preconditioner: unknown preconditioner 'jacoby'"),
                        HasSubstr("did you mean 'jacobi'"),
                        HasSubstr("'none', 'jacobi', 'sgs', 'ic', 'cholesky', 'amg'"))));
}

TEST(LinearSolverOptions, CholeskyPreconditionerOnlyWithCg) {
  EXPECT_THAT([] { Parse(R"({"type": "ldlt", "preconditioner": "cholesky"})"); },
              ThrowsMessage<InputError>(
                  AllOf(HasSubstr("scene.json: solver.preconditioner: "),
                        HasSubstr("'cholesky' applies to type 'cg' only (type is 'ldlt')"))));
  EXPECT_NO_THROW(Parse(R"({"type": "ldlt", "preconditioner": "ic"})"));
}

TEST(LinearSolverOptions, AmgPreconditionerOnlyWithCg) {
  EXPECT_EQ(Parse(R"({"type": "cg", "preconditioner": "amg"})").preconditioner, "amg");
  EXPECT_THAT([] { Parse(R"({"type": "cholmod", "preconditioner": "amg"})"); },
              ThrowsMessage<InputError>(
                  AllOf(HasSubstr("scene.json: solver.preconditioner: "),
                        HasSubstr("'amg' applies to type 'cg' only (type is 'cholmod')"))));
  LinearSolverOptions options;
  options.type = "ldlt";
  options.preconditioner = "amg";
  EXPECT_THROW((void)MakeLinearSolver(options), InputError);
}

TEST(LinearSolverOptions, BadNumbersNameTheirPath) {
  EXPECT_THAT([] { Parse(R"({"tolerance": 0})"); },
              ThrowsMessage<InputError>(
                  HasSubstr("scene.json: solver.tolerance: expected a positive number")));
  EXPECT_THAT([] { Parse(R"({"max_iterations": 0})"); },
              ThrowsMessage<InputError>(HasSubstr("solver.max_iterations: expected an integer")));
  EXPECT_THAT([] { Parse(R"({"max_iterations": 1e12})"); },
              ThrowsMessage<InputError>(HasSubstr("solver.max_iterations:")));
  EXPECT_THAT([] { Parse(R"({"refactor_iterations": -1})"); },
              ThrowsMessage<InputError>(HasSubstr("solver.refactor_iterations: expected")));
  EXPECT_EQ(Parse(R"({"refactor_iterations": 0})").refactor_iterations, 0);
}

TEST(LinearSolverOptions, UnknownKeyNamesPathAndSuggests) {
  EXPECT_THAT([] { Parse(R"({"tolerence": 1e-6})"); },
              ThrowsMessage<InputError>(AllOf(HasSubstr("scene.json: solver: unknown key "
                                                        "'tolerence'"),
                                              HasSubstr("did you mean 'tolerance'"))));
}

TEST(MakeLinearSolver, UnknownTypeOrPreconditionerThrowsListingChoices) {
  LinearSolverOptions options;
  options.type = "gmres";
  EXPECT_THAT([&] { (void)MakeLinearSolver(options); },
              ThrowsMessage<InputError>(AllOf(HasSubstr("unknown linear solver type 'gmres'"),
                                              HasSubstr("'cg', 'ldlt', 'cholmod'"))));
  options.type = "cg";
  options.preconditioner = "ilu";
  EXPECT_THAT(
      [&] { (void)MakeLinearSolver(options); },
      ThrowsMessage<InputError>(AllOf(HasSubstr("unknown preconditioner 'ilu'"),
                                      HasSubstr("'none', 'jacobi', 'sgs', 'ic', 'cholesky'"))));
}

TEST(MakeLinearSolver, RejectsCholeskyWithDirectTypeAndBadNumbers) {
  LinearSolverOptions options;
  options.type = "cholmod";
  options.preconditioner = "cholesky";
  EXPECT_THROW((void)MakeLinearSolver(options), InputError);
  options = {};
  options.tolerance = -1.0;
  EXPECT_THAT([&] { (void)MakeLinearSolver(options); },
              ThrowsMessage<InputError>(HasSubstr("tolerance must be a positive number")));
  options = {};
  options.max_iterations = 0;
  EXPECT_THROW((void)MakeLinearSolver(options), InputError);
  options = {};
  options.refactor_iterations = -2;
  EXPECT_THROW((void)MakeLinearSolver(options), InputError);
}

}  // namespace
}  // namespace gipsi
