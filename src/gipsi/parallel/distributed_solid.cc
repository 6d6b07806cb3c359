/// @file
/// A FemSolid's part on one rank: partition, shared sums and the PETSc solve of its tangent.

#include "gipsi/parallel/distributed_solid.h"

#include <fmt/format.h>
#include <petscksp.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/base/state.h"
#include "gipsi/parallel/petsc_check.h"

namespace gipsi {
namespace {

// Global PETSc index of every local dof (3 per local node, node-major).
std::vector<PetscInt> GlobalDofs(const MeshPart& part) {
  std::vector<PetscInt> dofs;
  dofs.reserve(3 * part.global.size());
  for (const std::int64_t g : part.global)
    for (int a = 0; a < 3; ++a) dofs.push_back(static_cast<PetscInt>(3 * g + a));
  return dofs;
}

// A ghosted vector of 3 entries per node: owned nodes, then the shared ones.
Vec MakeGhosted(const MeshPart& part, MPI_Comm comm) {
  std::vector<PetscInt> ghosts;
  for (std::size_t i = static_cast<std::size_t>(part.num_owned); i < part.global.size(); ++i)
    ghosts.push_back(static_cast<PetscInt>(part.global[i]));
  Vec v = nullptr;
  GIPSI_PETSC(VecCreateGhostBlock(comm, 3, static_cast<PetscInt>(3 * part.num_owned),
                                  static_cast<PetscInt>(3 * part.num_global_nodes),
                                  static_cast<PetscInt>(ghosts.size()), ghosts.data(), &v));
  return v;
}

// Copies `n` values between a ghosted vector's local form and `data` (to_vec: into it).
void CopyLocalForm(Vec ghosted, double* data, std::size_t n, bool to_vec) {
  Vec local = nullptr;
  PetscScalar* array = nullptr;
  GIPSI_PETSC(VecGhostGetLocalForm(ghosted, &local));
  GIPSI_PETSC(VecGetArray(local, &array));
  if (to_vec)
    std::copy(data, data + n, array);
  else
    std::copy(array, array + n, data);
  GIPSI_PETSC(VecRestoreArray(local, &array));
  GIPSI_PETSC(VecGhostRestoreLocalForm(ghosted, &local));
}

/// The whole tangent as one PETSc system (distributed_solid.h says which KSP and PC).
class PetscSolidSolver final : public LinearSolver {
 public:
  PetscSolidSolver(MPI_Comm comm, const MeshPart& part, LinearSolverOptions options,
                   const VecX& rest)
      : comm_(comm), part_(part), options_(std::move(options)), dofs_(GlobalDofs(part)) {
    direct_ = options_.type != "cg";
    lagged_ = !direct_ && (options_.preconditioner == "amg" || options_.preconditioner == "hypre");
    GIPSI_PETSC(KSPCreate(comm_, &ksp_));
    GIPSI_PETSC(KSPSetOptionsPrefix(ksp_, "solid_"));
    GIPSI_PETSC(KSPSetType(ksp_, direct_ ? KSPPREONLY : KSPCG));
    PC pc = nullptr;
    GIPSI_PETSC(KSPGetPC(ksp_, &pc));
    const std::string& pre = options_.preconditioner;
    if (direct_) {
      // The tangent gathered on every rank and factorised there by a sequential solver
      // (PCREDUNDANT): the serial object's own (CHOLMOD's supernodal LLᵀ, UMFPACK's LU), or
      // MUMPS's LDLᵀ for "ldlt" and for an indefinite tangent (AcceptIndefinite). MUMPS across
      // ranks schedules its work dynamically and gave other bits in every run (the ventricle
      // inflation on 2 ranks), so a checkpoint would not resume bitwise. The price: each rank
      // holds the whole factorisation (docs/scale-out.md).
      GIPSI_PETSC(PCSetType(pc, PCREDUNDANT));
      factor_solver_ = options_.type == "cholmod"   ? MATSOLVERCHOLMOD
                       : options_.type == "umfpack" ? MATSOLVERUMFPACK
                                                    : MATSOLVERMUMPS;
      // CHOLMOD's own report of an indefinite tangent would repeat, on every rank, what the
      // object's warning says (Newton switches to LDLᵀ); PETSC_OPTIONS may still ask for it.
      PetscBool given = PETSC_FALSE;
      GIPSI_PETSC(
          PetscOptionsHasName(nullptr, nullptr, "-solid_redundant_mat_cholmod_print", &given));
      if (!given)
        GIPSI_PETSC(PetscOptionsSetValue(nullptr, "-solid_redundant_mat_cholmod_print", "0"));
      GIPSI_PETSC(PCSetType(InnerPc(), options_.type == "umfpack" ? PCLU : PCCHOLESKY));
      GIPSI_PETSC(PCFactorSetMatSolverType(InnerPc(), factor_solver_.c_str()));
    } else if (pre == "amg") {
      // The hierarchy is built anew for every tangent: reusing the prolongators (PETSc's
      // default) kept stale smoother eigenvalue estimates, and CG met an indefinite
      // preconditioner on the swinging cantilever on 4 ranks.
      GIPSI_PETSC(PCSetType(pc, PCGAMG));
      GIPSI_PETSC(PCGAMGSetReuseInterpolation(pc, PETSC_FALSE));
    } else if (pre == "hypre") {
      GIPSI_PETSC(PCSetType(pc, PCHYPRE));
    } else if (pre == "jacobi") {
      // Each node's 3×3 block, given as variable blocks of 3 (AnalyzePattern): PETSc 3.18's
      // PCPBJACOBI reads the block size of the diagonal part, which MatSetPreallocationCOO
      // leaves at 1 on more than one rank, and so applied a wrong, indefinite preconditioner.
      GIPSI_PETSC(PCSetType(pc, PCVPBJACOBI));
    } else if (pre == "sgs") {
      GIPSI_PETSC(PCSetType(pc, PCSOR));
      GIPSI_PETSC(PCSORSetSymmetric(pc, SOR_LOCAL_SYMMETRIC_SWEEP));
    } else {
      GIPSI_PETSC(PCSetType(pc, PCNONE));
    }
    GIPSI_PETSC(KSPSetTolerances(ksp_, options_.tolerance, 1e-300, PETSC_DEFAULT,
                                 static_cast<PetscInt>(options_.max_iterations)));
    if (!direct_) {
      GIPSI_PETSC(KSPSetNormType(ksp_, KSP_NORM_UNPRECONDITIONED));
      GIPSI_PETSC(KSPSetInitialGuessNonzero(ksp_, PETSC_TRUE));
    }
    GIPSI_PETSC(KSPSetFromOptions(ksp_));
    solution_ = MakeGhosted(part_, comm_);
    GIPSI_PETSC(VecDuplicate(solution_, &rhs_));
    GIPSI_PETSC(VecDuplicate(solution_, &work_));
    if (!direct_ && pre == "amg") {
      // The rest positions of the owned nodes: GAMG's rigid-body near-null space.
      Vec coords = nullptr;
      GIPSI_PETSC(VecCreateMPI(comm_, static_cast<PetscInt>(3 * part_.num_owned), PETSC_DETERMINE,
                               &coords));
      GIPSI_PETSC(VecSetBlockSize(coords, 3));
      PetscScalar* array = nullptr;
      GIPSI_PETSC(VecGetArray(coords, &array));
      std::copy(rest.data(), rest.data() + 3 * part_.num_owned, array);
      GIPSI_PETSC(VecRestoreArray(coords, &array));
      GIPSI_PETSC(MatNullSpaceCreateRigidBody(coords, &near_null_));
      GIPSI_PETSC(VecDestroy(&coords));
    }
  }
  ~PetscSolidSolver() override {
    MatNullSpaceDestroy(&near_null_);
    KSPDestroy(&ksp_);
    MatDestroy(&matrix_);
    VecDestroy(&work_);
    VecDestroy(&rhs_);
    VecDestroy(&solution_);
  }

  [[nodiscard]] std::string name() const override {
    KSPType type = nullptr;
    PCType pc_type = nullptr;
    PC pc = nullptr;
    KSPGetType(ksp_, &type);
    KSPGetPC(ksp_, &pc);
    PCGetType(pc, &pc_type);
    if (direct_)
      return fmt::format("petsc {} (redundant)",
                         factor_solver_ == MATSOLVERMUMPS ? "mumps ldlt" : factor_solver_);
    return fmt::format("petsc {}+{}", type != nullptr ? type : "?",
                       pc_type != nullptr ? pc_type : "?");
  }
  // MUMPS factorises a symmetric matrix as LDLᵀ with pivoting: indefinite tangents too. CHOLMOD
  // (LLᵀ) gives way to it, for good, as the serial "cholmod" gives way to its LDLᵀ.
  bool AcceptIndefinite() override {
    if (!direct_ || options_.type == "umfpack") return direct_;
    if (factor_solver_ != std::string_view(MATSOLVERMUMPS)) {
      PC pc = nullptr;
      GIPSI_PETSC(KSPGetPC(ksp_, &pc));
      GIPSI_PETSC(PCReset(pc));
      factor_solver_ = MATSOLVERMUMPS;
      GIPSI_PETSC(PCFactorSetMatSolverType(InnerPc(), factor_solver_.c_str()));
    }
    return true;
  }

  void AnalyzePattern(const SparseMatrix& A) override {
    GIPSI_CHECK(A.rows() == A.cols() && A.rows() == static_cast<Index>(dofs_.size()) &&
                A.isCompressed());
    const auto entries = static_cast<std::size_t>(A.nonZeros());
    std::vector<PetscInt> rows(entries), cols(entries);
    for (Index j = 0; j < A.outerSize(); ++j)
      for (int at = A.outerIndexPtr()[j]; at < A.outerIndexPtr()[j + 1]; ++at) {
        rows[static_cast<std::size_t>(at)] = dofs_[static_cast<std::size_t>(A.innerIndexPtr()[at])];
        cols[static_cast<std::size_t>(at)] = dofs_[static_cast<std::size_t>(j)];
      }
    GIPSI_PETSC(MatDestroy(&matrix_));
    GIPSI_PETSC(MatCreate(comm_, &matrix_));
    const auto owned = static_cast<PetscInt>(3 * part_.num_owned);
    const auto global = static_cast<PetscInt>(3 * part_.num_global_nodes);
    GIPSI_PETSC(MatSetSizes(matrix_, owned, owned, global, global));
    GIPSI_PETSC(MatSetType(matrix_, MATAIJ));
    GIPSI_PETSC(MatSetBlockSize(matrix_, 3));
    GIPSI_PETSC(MatSetOption(matrix_, MAT_SYMMETRIC, PETSC_TRUE));
    GIPSI_PETSC(MatSetPreallocationCOO(matrix_, static_cast<PetscCount>(entries), rows.data(),
                                       cols.data()));
    if (near_null_ != nullptr) GIPSI_PETSC(MatSetNearNullSpace(matrix_, near_null_));
    if (!direct_ && options_.preconditioner == "jacobi") {
      std::vector<PetscInt> blocks(static_cast<std::size_t>(part_.num_owned), 3);
      GIPSI_PETSC(
          MatSetVariableBlockSizes(matrix_, static_cast<PetscInt>(blocks.size()), blocks.data()));
    }
    entries_ = A.nonZeros();
    factorized_ = false;
  }

  bool Factorize(const SparseMatrix& A) override {
    if (matrix_ == nullptr) AnalyzePattern(A);
    GIPSI_CHECK(A.nonZeros() == entries_ && A.rows() == static_cast<Index>(dofs_.size()));
    factorized_ = false;
    refactorized_ = true;
    double bad = Eigen::Map<const VecX>(A.valuePtr(), A.nonZeros()).allFinite() ? 0.0 : 1.0;
    MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_DOUBLE, MPI_MAX, comm_);
    if (bad > 0) return false;
    GIPSI_PETSC(MatSetValuesCOO(matrix_, A.valuePtr(), INSERT_VALUES));
    current_ = A.valuePtr();
    if (lagged_ && have_pc_ && !rebuild_pending_) {  // the multigrid of an earlier tangent
      GIPSI_PETSC(KSPSetReusePreconditioner(ksp_, PETSC_TRUE));
      GIPSI_PETSC(KSPSetOperators(ksp_, matrix_, matrix_));
      refactorized_ = false;
      factorized_ = true;
      return true;
    }
    factorized_ = Build();
    return factorized_;
  }

  // GAMG on a mesh it coarsens poorly (a box cut into 5 tets per cell: operator complexity 4.6,
  // against 1.2 on the 6-tet cut and 1.3 on the liver; docs/performance.md) costs that many
  // times the tangent's work per iteration, where BoomerAMG or block Jacobi were twice as fast.
  // Said once, on the first hierarchy built, by every rank alike (the complexity is global).
  void NoteComplexity(PC pc) {
    if (complexity_noted_) return;
    complexity_noted_ = true;
    constexpr double kPoorCoarsening = 3.0;
    PetscReal grid = 0, operators = 0;
    GIPSI_PETSC(PCMGGetGridComplexity(pc, &grid, &operators));
    if (operators > kPoorCoarsening)
      Log().warn(
          "a split FemSolid: GAMG's levels hold {:.2g} times the tangent's nonzeros (its operator "
          "complexity; 1.2-1.3 where it coarsens well), so each CG iteration costs as much more. "
          "A box cut into 5 tets per cell coarsens so: there \"parallel\": {{\"linear_solver\": "
          "{{\"preconditioner\": \"hypre\"}}}} (or \"jacobi\") was about twice as fast, or cut "
          "it into 6 (docs/scale-out.md, \"Solid mechanics\")",
          operators);
  }

  // Sets the preconditioner up for the matrix's current values (current_).
  bool Build() {
    have_pc_ = false;
    GIPSI_PETSC(KSPSetReusePreconditioner(ksp_, PETSC_FALSE));
    GIPSI_PETSC(KSPSetOperators(ksp_, matrix_, matrix_));
    // A factorisation that fails (a singular tangent) is a failed Factorize, not an error.
    PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
    const PetscErrorCode code = KSPSetUp(ksp_);
    PetscPopErrorHandler();
    PC pc = nullptr;
    PCFailedReason reason = PC_NOERROR;
    GIPSI_PETSC(KSPGetPC(ksp_, &pc));
    GIPSI_PETSC(PCGetFailedReasonRank(pc, &reason));
    double failed = code != 0 || reason != PC_NOERROR ? 1.0 : 0.0;
    MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_DOUBLE, MPI_MAX, comm_);
    have_pc_ = failed == 0;
    if (have_pc_ && !direct_ && options_.preconditioner == "amg") NoteComplexity(pc);
    rebuild_pending_ = false;
    fresh_ = true;
    if (lagged_ && have_pc_ && current_ != pc_source_.data())
      pc_source_.assign(current_, current_ + entries_);
    return have_pc_;
  }

  // A kept multigrid is saved as the values it was built from, and built again on restore
  // (GAMG and BoomerAMG are deterministic on the same rank count), so a resumed run solves with
  // the same preconditioner as the uninterrupted one.
  void SaveState(StateWriter& out) const override {
    out.BeginSection("PetscSolidSolver", 1);
    out.WriteBool(lagged_ && have_pc_);
    if (lagged_ && have_pc_) {
      out.WriteArray(std::span<const double>(pc_source_));
      out.WriteBool(rebuild_pending_);
      out.WriteInt(baseline_);
    }
    out.EndSection();
  }
  void RestoreState(StateReader& in, const SparseMatrix& current) override {
    in.BeginSection("PetscSolidSolver", 1);
    if (in.ReadBool()) {
      if (!lagged_) in.Fail("the checkpoint keeps a multigrid preconditioner this solver has not");
      if (matrix_ == nullptr) AnalyzePattern(current);
      pc_source_.resize(static_cast<std::size_t>(entries_));
      in.ReadArrayExact(pc_source_, "the values the kept multigrid was built from");
      GIPSI_PETSC(MatSetValuesCOO(matrix_, pc_source_.data(), INSERT_VALUES));
      current_ = pc_source_.data();
      if (!Build()) in.Fail("the saved multigrid cannot be built again");
      fresh_ = false;
      rebuild_pending_ = in.ReadBool();
      baseline_ = static_cast<int>(in.ReadInt());
      // The operator is the current matrix, with the kept preconditioner.
      GIPSI_PETSC(MatSetValuesCOO(matrix_, current.valuePtr(), INSERT_VALUES));
      current_ = current.valuePtr();
      GIPSI_PETSC(KSPSetReusePreconditioner(ksp_, PETSC_TRUE));
      GIPSI_PETSC(KSPSetOperators(ksp_, matrix_, matrix_));
      factorized_ = true;
      refactorized_ = false;
    }
    in.EndSection();
  }

  LinearSolveStats Solve(const VecX& b, VecX& x) override {
    LinearSolveStats stats;
    stats.refactorized = refactorized_;
    refactorized_ = false;
    const auto local = static_cast<std::size_t>(3 * part_.num_local());
    GIPSI_CHECK(b.size() == static_cast<Index>(local),
                "PETSc solve: a right-hand side of {} for {}", b.size(), local);
    if (!factorized_) {
      stats.relative_residual = std::numeric_limits<double>::infinity();
      return stats;
    }
    CopyLocalForm(rhs_, const_cast<double*>(b.data()), local, true);
    if (direct_ || x.size() != b.size())
      GIPSI_PETSC(VecSet(solution_, 0.0));
    else
      CopyLocalForm(solution_, x.data(), local, true);
    PetscReal b_norm = 0;
    GIPSI_PETSC(VecNorm(rhs_, NORM_2, &b_norm));
    x.resize(b.size());
    if (b_norm == 0) {
      x.setZero();
      stats.converged = true;
      return stats;
    }
    if (!std::isfinite(b_norm)) {
      stats.relative_residual = b_norm;
      return stats;
    }
    // A lagged multigrid that fails is rebuilt for this matrix, and the solve runs again.
    double relative = Iterate(b_norm, stats);
    if (lagged_ && !fresh_ && !(relative <= options_.tolerance)) {
      stats.refactorized = true;
      if (Build()) {
        GIPSI_PETSC(VecSet(solution_, 0.0));
        relative = Iterate(b_norm, stats);
      }
    }
    if (lagged_) {
      // The serial "amg" rule (pcg.cc): a fresh multigrid sets the baseline; a lagged one is
      // rebuilt at the next Factorize once CG needs more than refactor_iterations and more
      // than 1.5 times (plus 2) the baseline, or fails.
      if (fresh_)
        baseline_ = stats.iterations;
      else if (!(relative <= options_.tolerance) ||
               (stats.iterations > options_.refactor_iterations &&
                2 * stats.iterations > 3 * baseline_ + 4))
        rebuild_pending_ = true;
      fresh_ = false;
    }
    stats.relative_residual = relative;
    stats.converged = std::isfinite(relative) && relative <= options_.tolerance;
    GIPSI_PETSC(VecGhostUpdateBegin(solution_, INSERT_VALUES, SCATTER_FORWARD));
    GIPSI_PETSC(VecGhostUpdateEnd(solution_, INSERT_VALUES, SCATTER_FORWARD));
    CopyLocalForm(solution_, x.data(), local, false);
    return stats;
  }

 private:
  // KSP from solution_'s current values; the relative true residual at the end. KSP tests its
  // recurrence's residual, and the serial solvers promise the true one: another round from the
  // last iterate settles the rare solve that stops just above it.
  double Iterate(PetscReal b_norm, LinearSolveStats& stats) {
    double relative = std::numeric_limits<double>::infinity();
    for (int round = 0; round < 3; ++round) {
      KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
      PetscInt its = 0;
      GIPSI_PETSC(KSPSolve(ksp_, rhs_, solution_));
      GIPSI_PETSC(KSPGetConvergedReason(ksp_, &reason));
      GIPSI_PETSC(KSPGetIterationNumber(ksp_, &its));
      stats.iterations += static_cast<int>(its);
      GIPSI_PETSC(MatMult(matrix_, solution_, work_));
      GIPSI_PETSC(VecAYPX(work_, -1.0, rhs_));
      PetscReal r_norm = 0;
      GIPSI_PETSC(VecNorm(work_, NORM_2, &r_norm));
      relative = r_norm / b_norm;
      if (reason < 0 || !std::isfinite(relative) || relative <= options_.tolerance || direct_)
        break;
    }
    return relative;
  }

  MPI_Comm comm_;
  const MeshPart& part_;
  LinearSolverOptions options_;
  std::vector<PetscInt> dofs_;  // global index of every local dof
  bool direct_ = false;
  std::string factor_solver_ = MATSOLVERMUMPS;  // of the direct types

  // The preconditioner of the redundant solve's inner KSP (direct types).
  PC InnerPc() const {
    PC pc = nullptr, inner_pc = nullptr;
    KSP inner = nullptr;
    GIPSI_PETSC(KSPGetPC(ksp_, &pc));
    GIPSI_PETSC(PCRedundantGetKSP(pc, &inner));
    GIPSI_PETSC(KSPGetPC(inner, &inner_pc));
    return inner_pc;
  }
  KSP ksp_ = nullptr;
  Mat matrix_ = nullptr;
  MatNullSpace near_null_ = nullptr;
  Vec solution_ = nullptr, rhs_ = nullptr, work_ = nullptr;
  Index entries_ = 0;
  bool factorized_ = false, refactorized_ = false;
  const double* current_ = nullptr;  // the matrix's values (the caller's, alive till Factorize)
  // A multigrid ("amg", "hypre") kept across tangents while it works (Solve's rule).
  bool lagged_ = false, have_pc_ = false, rebuild_pending_ = true, fresh_ = false;
  bool complexity_noted_ = false;  // NoteComplexity said its piece
  int baseline_ = 0;               // CG iterations of the first solve with a fresh multigrid
  std::vector<double> pc_source_;  // the values the kept multigrid was built from
};

}  // namespace

struct DistributedSolid::Ghosts {
  Vec v = nullptr;
  ~Ghosts() { VecDestroy(&v); }
};

DistributedSolid::DistributedSolid(std::shared_ptr<const Mesh> whole_mesh, MPI_Comm comm)
    : comm_(comm),
      whole_(std::move(whole_mesh)),
      part_(PartitionMesh(*whole_, comm)),
      whole_boundary_(MakeBoundary(*whole_)),
      ghosts_(std::make_unique<Ghosts>()) {
  // The part's boundary: the whole boundary's faces of local tets, and every local node on the
  // whole boundary as a vertex (in local order).
  const Mesh& whole = *whole_;
  const BoundarySurface& whole_boundary = whole_boundary_;
  std::vector<int> whole_vertex_of_node(static_cast<std::size_t>(whole.num_nodes()), -1);
  for (std::size_t v = 0; v < whole_boundary.vertex_to_node.size(); ++v)
    whole_vertex_of_node[static_cast<std::size_t>(whole_boundary.vertex_to_node[v])] =
        static_cast<int>(v);
  std::vector<int> part_vertex(whole_boundary.vertex_to_node.size(), -1);
  for (std::size_t i = 0; i < part_.whole_node.size(); ++i) {
    const int v = whole_vertex_of_node[static_cast<std::size_t>(part_.whole_node[i])];
    if (v < 0) continue;
    part_vertex[static_cast<std::size_t>(v)] = static_cast<int>(whole_vertex_.size());
    whole_vertex_.push_back(v);
    boundary_.vertex_to_node.push_back(static_cast<int>(i));
  }
  std::vector<int> local_tet(static_cast<std::size_t>(whole.num_tets()), -1);
  for (std::size_t e = 0; e < part_.whole_tet.size(); ++e)
    local_tet[static_cast<std::size_t>(part_.whole_tet[e])] = static_cast<int>(e);
  std::vector<int> faces;
  for (Index f = 0; f < whole_boundary.num_triangles(); ++f) {
    const int tet = local_tet[static_cast<std::size_t>(
        whole_boundary.face_to_tet[static_cast<std::size_t>(f)])];
    if (tet < 0) continue;
    faces.push_back(static_cast<int>(f));
    boundary_.face_to_tet.push_back(tet);
  }
  boundary_.triangles.resize(3, static_cast<Index>(faces.size()));
  for (std::size_t k = 0; k < faces.size(); ++k)
    for (int a = 0; a < 3; ++a)
      boundary_.triangles(a, static_cast<Index>(k)) =
          part_vertex[static_cast<std::size_t>(whole_boundary.triangles(a, faces[k]))];
  whole_face_ = std::move(faces);
  whole_vertices_ = whole_boundary.num_vertices();
  whole_faces_ = whole_boundary.num_triangles();
  ghosts_->v = MakeGhosted(part_, comm_);
}

DistributedSolid::DistributedSolid(MeshPart part, MPI_Comm comm)
    : comm_(comm),
      part_(std::move(part)),
      boundary_(PartBoundary(part_, comm)),
      ghosts_(std::make_unique<Ghosts>()) {
  WholeBoundaryNumbers numbers = NumberOnWholeBoundary(part_, boundary_, comm_);
  whole_vertex_ = std::move(numbers.vertex);
  whole_face_ = std::move(numbers.face);
  whole_vertices_ = numbers.whole_vertices;
  whole_faces_ = numbers.whole_faces;
  ghosts_->v = MakeGhosted(part_, comm_);
}

DistributedSolid::~DistributedSolid() = default;

WholeFaceSelection DistributedSolid::SelectWholeFaces(const Region& region) const {
  const std::vector<int> local =
      SelectPartBoundaryFaces(region, part_, boundary_, WholeRegionTolerance(part_, comm_), comm_);
  // Each selected face is one rank's (a face of its tet): its number on the whole boundary
  // and its three whole-mesh nodes, in the whole boundary's vertex order.
  std::vector<int> mine;
  mine.reserve(4 * local.size());
  for (const int f : local) {
    mine.push_back(whole_face_[static_cast<std::size_t>(f)]);
    for (int a = 0; a < 3; ++a)
      mine.push_back(part_.whole_node[static_cast<std::size_t>(
          boundary_.vertex_to_node[static_cast<std::size_t>(boundary_.triangles(a, f))])]);
  }
  const std::vector<int> all = GatherAll(mine, comm_);
  const std::size_t count = all.size() / 4;
  std::vector<std::size_t> order(count);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&all](std::size_t a, std::size_t b) { return all[4 * a] < all[4 * b]; });
  WholeFaceSelection out;
  std::vector<int>& nodes = out.surface.vertex_to_node;
  for (std::size_t k = 0; k < count; ++k)
    nodes.insert(nodes.end(), all.begin() + static_cast<std::ptrdiff_t>(4 * k + 1),
                 all.begin() + static_cast<std::ptrdiff_t>(4 * k + 4));
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  out.surface.triangles.resize(3, static_cast<Index>(count));
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t at = 4 * order[k];
    out.faces.push_back(all[at]);
    for (int a = 0; a < 3; ++a)
      out.surface.triangles(a, static_cast<Index>(k)) = static_cast<int>(
          std::lower_bound(nodes.begin(), nodes.end(), all[at + 1 + static_cast<std::size_t>(a)]) -
          nodes.begin());
  }
  return out;
}

const Mesh& DistributedSolid::whole_mesh() const {
  GIPSI_CHECK(whole_ != nullptr, "a FemSolid split from mesh blocks has no whole mesh");
  return *whole_;
}

const BoundarySurface& DistributedSolid::whole_boundary() const {
  GIPSI_CHECK(whole_ != nullptr, "a FemSolid split from mesh blocks has no whole mesh");
  return whole_boundary_;
}

void DistributedSolid::Reduce(std::span<double> values, bool max) const {
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE,
                max ? MPI_MAX : MPI_SUM, comm_);
}

void DistributedSolid::SumShared(VecX& v) const {
  const auto local = static_cast<std::size_t>(3 * part_.num_local());
  GIPSI_CHECK(v.size() == static_cast<Index>(local));
  CopyLocalForm(ghosts_->v, v.data(), local, true);
  // The shared copies' partial sums onto their owners, then the owners' totals back.
  GIPSI_PETSC(VecGhostUpdateBegin(ghosts_->v, ADD_VALUES, SCATTER_REVERSE));
  GIPSI_PETSC(VecGhostUpdateEnd(ghosts_->v, ADD_VALUES, SCATTER_REVERSE));
  GIPSI_PETSC(VecGhostUpdateBegin(ghosts_->v, INSERT_VALUES, SCATTER_FORWARD));
  GIPSI_PETSC(VecGhostUpdateEnd(ghosts_->v, INSERT_VALUES, SCATTER_FORWARD));
  CopyLocalForm(ghosts_->v, v.data(), local, false);
}

std::unique_ptr<LinearSolver> DistributedSolid::MakeLinearSolver(const LinearSolverOptions& options,
                                                                 const VecX& rest) const {
  if (options.type == "cg" &&
      (options.preconditioner == "ic" || options.preconditioner == "cholesky"))
    throw InputError(fmt::format(
        "preconditioner '{}' has no distributed version: use 'amg' (PETSc's GAMG, the default "
        "under MPI), 'hypre', 'jacobi', 'sgs' or 'none', e.g. in the object's \"parallel\": "
        "{{\"linear_solver\": {{...}}}} block",
        options.preconditioner));
  if (options.type == "schur_gmres")
    throw InputError("linear_solver type 'schur_gmres' is a MixedSolid's, not a FemSolid's");
  return std::make_unique<PetscSolidSolver>(comm_, part_, options, rest);
}

std::int64_t DistributedSolid::WholeTetId(Index local) const {
  const Mesh& mesh = *part_.mesh;
  return mesh.tet_ids.empty() ? part_.whole_tet[static_cast<std::size_t>(local)]
                              : mesh.TetId(local);
}

}  // namespace gipsi
