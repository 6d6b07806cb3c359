// Solver selection: validation of LinearSolverOptions, the factory, and the JSON reader.

#include "gipsi/numerics/sparse/linear_solver.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/numerics/sparse/cg_kernels.h"
#include "gipsi/numerics/sparse/solvers.h"

namespace gipsi {
namespace {

constexpr std::array<std::string_view, 5> kTypes = {"cg", "ldlt", "cholmod", "umfpack",
                                                    "schur_gmres"};
constexpr std::array<std::string_view, 6> kPreconditioners = {"none", "jacobi",   "sgs",
                                                              "ic",   "cholesky", "amg"};

/// Empty if `value` is one of `choices`, else e.g. "unknown linear solver type 'gmres';
/// choices: 'cg', 'ldlt', 'cholmod', 'umfpack'" (with a "did you mean" for a near miss).
template <std::size_t N>
std::optional<std::string> CheckChoice(std::string_view what, std::string_view value,
                                       const std::array<std::string_view, N>& choices) {
  if (std::find(choices.begin(), choices.end(), value) != choices.end()) return std::nullopt;
  std::vector<std::string> names(choices.begin(), choices.end());
  std::string list;
  for (const std::string& name : names)
    list += fmt::format("{}'{}'", list.empty() ? "" : ", ", name);
  return fmt::format("unknown {} '{}'{}; choices: {}", what, value, SuggestClosest(value, names),
                     list);
}

/// The lagged preconditioners ("cholesky", "amg") make sense only inside CG.
std::optional<std::string> CholeskyNeedsCg(const LinearSolverOptions& options) {
  if ((options.preconditioner == "cholesky" || options.preconditioner == "amg") &&
      options.type != "cg")
    return fmt::format("preconditioner '{}' applies to type 'cg' only (type is '{}')",
                       options.preconditioner, options.type);
  return std::nullopt;
}

/// A string member that must be one of `choices`.
template <std::size_t N>
std::string ReadChoice(const JsonNode& node, std::string_view what,
                       const std::array<std::string_view, N>& choices) {
  if (!node.is_string()) node.Expected("a string");
  std::string value = node.AsString();
  if (auto complaint = CheckChoice(what, value, choices)) node.Fail(*complaint);
  return value;
}

/// An integer in [minimum, INT_MAX].
int ReadInt(const JsonNode& node, int minimum) {
  const std::int64_t value = node.AsInt();
  if (value < minimum || value > std::numeric_limits<int>::max())
    node.Fail(fmt::format("expected an integer in [{}, {}], got {}", minimum,
                          std::numeric_limits<int>::max(), value));
  return static_cast<int>(value);
}

}  // namespace

Eigen::MatrixXd RigidBodyModes(const VecX& positions) {
  GIPSI_CHECK(positions.size() % 3 == 0, "RigidBodyModes: {} coordinates is not a multiple of 3",
              positions.size());
  const Index nodes = positions.size() / 3;
  Vec3 centre = Vec3::Zero();
  for (Index i = 0; i < nodes; ++i) centre += positions.segment<3>(3 * i);
  if (nodes > 0) centre /= static_cast<double>(nodes);
  Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(positions.size(), 6);
  for (Index i = 0; i < nodes; ++i) {
    const Vec3 p = positions.segment<3>(3 * i) - centre;
    for (int a = 0; a < 3; ++a) modes(3 * i + a, a) = 1.0;
    // Rotations about x, y, z: ω × p.
    modes(3 * i + 1, 3) = -p.z();
    modes(3 * i + 2, 3) = p.y();
    modes(3 * i + 0, 4) = p.z();
    modes(3 * i + 2, 4) = -p.x();
    modes(3 * i + 0, 5) = -p.y();
    modes(3 * i + 1, 5) = p.x();
  }
  return modes;
}

bool AllValuesFinite(const SparseMatrix& A) { return AllFiniteValues(A.valuePtr(), A.nonZeros()); }

void CheckAnalysedShape(const SparseMatrix& A, Index rows, Index nonzeros, const char* who) {
  GIPSI_CHECK(A.rows() == A.cols() && A.isCompressed(), "{}: matrix must be square and compressed",
              who);
  GIPSI_CHECK(A.rows() == rows && A.nonZeros() == nonzeros,
              "{}: matrix ({} rows, {} nonzeros) does not have the analysed pattern ({} rows, {} "
              "nonzeros); call AnalyzePattern first",
              who, A.rows(), A.nonZeros(), rows, nonzeros);
}

std::unique_ptr<LinearSolver> MakeLinearSolver(const LinearSolverOptions& options) {
  if (auto complaint = CheckChoice("linear solver type", options.type, kTypes))
    throw InputError(*complaint);
  if (auto complaint = CheckChoice("preconditioner", options.preconditioner, kPreconditioners))
    throw InputError(*complaint);
  if (auto complaint = CholeskyNeedsCg(options)) throw InputError(*complaint);
  if (!(options.tolerance > 0.0) || !std::isfinite(options.tolerance))
    throw InputError(fmt::format("linear solver tolerance must be a positive number, got {}",
                                 options.tolerance));
  if (options.max_iterations < 1)
    throw InputError(
        fmt::format("linear solver max_iterations must be ≥ 1, got {}", options.max_iterations));
  if (options.refactor_iterations < 0)
    throw InputError(fmt::format("linear solver refactor_iterations must be ≥ 0, got {}",
                                 options.refactor_iterations));
  if (options.type == "ldlt") return MakeLdltSolver(options);
  if (options.type == "cholmod") return MakeCholmodSolver(options);
  if (options.type == "umfpack") return MakeUmfpackSolver(options);
  if (options.type == "schur_gmres")
    throw InputError(
        "linear solver type 'schur_gmres' solves the saddle points of mixed elements (a "
        "MixedSolid's); this object's systems are not saddle points");
  return MakePcgSolver(options);
}

LinearSolverOptions ParseLinearSolverOptions(const JsonNode& node, bool saddle_point) {
  node.CheckKeys({"type", "preconditioner", "tolerance", "max_iterations", "refactor_iterations"});
  LinearSolverOptions options;
  if (auto type = node.Find("type")) {
    options.type = ReadChoice(*type, "linear solver type", kTypes);
    if (options.type == "schur_gmres" && !saddle_point)
      type->Fail(
          "'schur_gmres' solves the saddle points of mixed elements (a MixedSolid's); this "
          "object's systems are not saddle points");
  }
  if (auto preconditioner = node.Find("preconditioner")) {
    options.preconditioner = ReadChoice(*preconditioner, "preconditioner", kPreconditioners);
    if (auto complaint = CholeskyNeedsCg(options)) preconditioner->Fail(*complaint);
  }
  options.tolerance = node.Positive("tolerance", options.tolerance);
  if (auto max_iterations = node.Find("max_iterations"))
    options.max_iterations = ReadInt(*max_iterations, 1);
  if (auto refactor = node.Find("refactor_iterations"))
    options.refactor_iterations = ReadInt(*refactor, 0);
  return options;
}

}  // namespace gipsi
