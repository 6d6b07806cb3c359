/// @file
/// The P1 monodomain on a partitioned mesh, its diffusion solved by PETSc.

#include "gipsi/parallel/distributed_monodomain.h"

#include <fmt/format.h>
#include <petscksp.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <variant>

#include "gipsi/base/error.h"
#include "gipsi/base/state_binding.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/models/ep/monodomain.h"
#include "gipsi/parallel/distributed_fibres.h"
#include "gipsi/parallel/petsc_check.h"
#include "gipsi/parallel/petsc_part.h"

namespace gipsi {
namespace {

// The worst of the ranks' step outcomes first: a divergence, then a failure, then a stop.
int Severity(StepStatus::Code code) {
  switch (code) {
    case StepStatus::Code::kDiverged:
      return 3;
    case StepStatus::Code::kFailed:
      return 2;
    case StepStatus::Code::kStopped:
      return 1;
    case StepStatus::Code::kOk:
      break;
  }
  return 0;
}

// Every stimulus and clamp region, selected on the whole mesh, becomes the list of this
// rank's local nodes in it (possibly none). A region that selects no node of the whole mesh
// is refused, on every rank alike, with Monodomain's message.
void LocaliseRegions(EpTissueParams& params, const Mesh& whole, const MeshPart& part) {
  std::vector<int> local_of(static_cast<std::size_t>(whole.num_nodes()), -1);
  for (std::size_t i = 0; i < part.whole_node.size(); ++i)
    local_of[static_cast<std::size_t>(part.whole_node[i])] = static_cast<int>(i);
  auto localise = [&](Region& region, const std::string& what) {
    const std::vector<int> nodes = SelectNodes(region, whole);
    if (nodes.empty()) throw InputError(fmt::format("{} selects no node of the domain", what));
    NodeIdsRegion ids;
    for (int n : nodes)
      if (local_of[static_cast<std::size_t>(n)] >= 0)
        ids.ids.push_back(local_of[static_cast<std::size_t>(n)]);
    region = std::move(ids);
  };
  for (StimulusSpec& s : params.stimuli) localise(s.region, fmt::format("stimulus '{}'", s.name));
  for (ClampSpec& c : params.clamps) localise(c.region, fmt::format("clamp '{}'", c.name));
}

// As LocaliseRegions, for a mesh no rank holds whole: each rank selects among its own nodes,
// geometric regions at the whole mesh's tolerance (its bounding box reduced over the ranks),
// node ids as whole-mesh indices; a region that selects no node on any rank is refused on
// every rank.
void LocaliseRegionsOnPart(EpTissueParams& params, const MeshPart& part, MPI_Comm comm) {
  const double tolerance = WholeRegionTolerance(part, comm);
  auto localise = [&](Region& region, const std::string& what) {
    NodeIdsRegion ids;
    try {
      ids.ids = SelectPartNodes(region, part, tolerance, comm);
    } catch (const InputError& e) {
      throw InputError(fmt::format("{}: {}", what, e.what()));
    }
    int found = ids.ids.empty() ? 0 : 1;
    MPI_Allreduce(MPI_IN_PLACE, &found, 1, MPI_INT, MPI_MAX, comm);
    if (found == 0) throw InputError(fmt::format("{} selects no node of the domain", what));
    region = std::move(ids);
  };
  for (StimulusSpec& s : params.stimuli) localise(s.region, fmt::format("stimulus '{}'", s.name));
  for (ClampSpec& c : params.clamps) localise(c.region, fmt::format("clamp '{}'", c.name));
}

// The object's "parallel" solver, where the scene gives one, replaces the serial one.
EpTissueParams UseDistributedSolver(EpTissueParams params) {
  if (params.distributed_linear) params.linear = *params.distributed_linear;
  return params;
}

}  // namespace

struct DistributedMonodomain::Petsc {
  Mat stiffness = nullptr;  // K
  Mat mass = nullptr;       // consistent M (when asked for)
  Mat system = nullptr;     // M + θΔt K
  Vec lumped = nullptr;     // lumped M, assembled over the ranks
  Vec v = nullptr;          // ghosted: owned entries, then the shared ones
  Vec rhs = nullptr, work = nullptr;
  KSP ksp = nullptr;
  double system_dt = -1;

  ~Petsc() {
    KSPDestroy(&ksp);
    VecDestroy(&work);
    VecDestroy(&rhs);
    VecDestroy(&v);
    VecDestroy(&lumped);
    MatDestroy(&system);
    MatDestroy(&mass);
    MatDestroy(&stiffness);
  }
};

DistributedMonodomain::DistributedMonodomain(std::string name, const Mesh& whole,
                                             EpTissueParams params, MPI_Comm comm)
    : DistributedMonodomain(std::move(name), std::move(params), comm,
                            PartitionMesh(CheckedDomain(whole), comm), &whole) {}

DistributedMonodomain::DistributedMonodomain(std::string name, MeshPart part, EpTissueParams params,
                                             MPI_Comm comm)
    : DistributedMonodomain(std::move(name), std::move(params), comm, std::move(part), nullptr) {}

const Mesh& DistributedMonodomain::CheckedDomain(const Mesh& whole) {
  if (whole.tets.cols() == 0)
    throw InputError("the Monodomain object needs a tetrahedral domain mesh (this one has none)");
  return whole;
}

DistributedMonodomain::DistributedMonodomain(std::string name, EpTissueParams params, MPI_Comm comm,
                                             MeshPart part, const Mesh* whole)
    : EpTissue(std::move(name), UseDistributedSolver(std::move(params))),
      comm_(comm),
      part_(std::move(part)) {
  if (params_.anisotropic() && !params_.fibre && !params_.fibre_rule)
    throw InputError(
        "the conductivity is anisotropic (longitudinal != transverse), so the object needs a "
        "fibre direction: add \"fibres\": {\"direction\": [1, 0, 0]}");
  const LinearSolverOptions& linear = params_.linear;
  if (linear.type != "cg" && linear.type != "cholmod" && linear.type != "ldlt")
    throw InputError(fmt::format(
        "the distributed monodomain solves with 'cg' or a direct Cholesky ('cholmod' or 'ldlt': "
        "MUMPS across ranks), not '{}'",
        linear.type));
  // "sgs" (block Gauss-Seidel) is Jacobi for this scalar matrix, serially and here.
  if (linear.type == "cg" && linear.preconditioner != "jacobi" && linear.preconditioner != "sgs" &&
      linear.preconditioner != "amg" && linear.preconditioner != "hypre" &&
      linear.preconditioner != "none")
    throw InputError(
        fmt::format("unknown preconditioner '{}' for the distributed monodomain; choices: 'none', "
                    "'jacobi', 'amg' (PETSc's GAMG), 'hypre' (BoomerAMG)",
                    linear.preconditioner));
  if (whole != nullptr)
    LocaliseRegions(params_, *whole, part_);
  else
    LocaliseRegionsOnPart(params_, part_, comm_);
  SetGeometry(part_.mesh, MakeBoundary(*part_.mesh));
  const Vec3 fibre = params_.fibre.value_or(Vec3::UnitX()).normalized();
  fibres_.resize(3, static_cast<Index>(part_.whole_tet.size()));
  if (params_.fibre_rule)  // solved over the ranks, with or without the whole mesh
    fibres_ = TransmuralFibresOnPart(part_, *params_.fibre_rule, comm_).fibre;
  else
    fibres_.colwise() = fibre;
  // As the serial object's, read-only: a written fibre would need the operator assembled anew.
  f_fibre_ = DeclareField({"fibre", FieldLocation::kElement, 3, "1", FieldAccess::kRead,
                           "fibre direction per element"});
  f_activated_ = FindField("activated_fraction");
  f_integral_ = FindField("voltage_integral");
  f_iterations_ = FindField("diffusion_iterations");
  InitTissue({.require_region_nodes = false, .serial_solver = false});
  petsc_ = std::make_unique<Petsc>();
  Assemble();
}

DistributedMonodomain::~DistributedMonodomain() = default;

void DistributedMonodomain::Assemble() {
  P1ScalarOperators ops = AssembleMonodomainOperators(domain(), fibres_, params_);
  Petsc& p = *petsc_;
  // K and M go to PETSc by their COO entries (global row, column), summed over the ranks where
  // nodes are shared; the system matrix M + θΔt K is then made from them on PETSc's side, so
  // this rank keeps no copy of their values (it held five: Eigen's K and M, their values in
  // COO order and the system's, about 130 B per tet).
  const SparseMatrix& k = ops.stiffness;
  const auto entries = static_cast<std::size_t>(k.nonZeros());
  if (!params_.lumped_mass) {
    const SparseMatrix& m = ops.consistent_mass;
    // Both come from every pair of nodes of every tet, so they share the pattern.
    if (m.nonZeros() != k.nonZeros() ||
        !std::equal(m.innerIndexPtr(), m.innerIndexPtr() + entries, k.innerIndexPtr()))
      throw std::logic_error("the P1 mass and stiffness matrices differ in pattern");
  }
  // Each local operator goes to PETSc and is then freed, which keeps the set-up peak down.
  auto make_matrix = [&](Mat* out, SparseMatrix& a) {
    MakePartMatrix(part_, a, comm_, out);
    a = SparseMatrix();
  };
  make_matrix(&p.stiffness, ops.stiffness);
  if (!params_.lumped_mass) make_matrix(&p.mass, ops.consistent_mass);
  // The system matrix has K's pattern (M's is the same): a copy of K's structure without its
  // COO tables, filled by SolveDiffusion whenever Δt changes.
  GIPSI_PETSC(MatDestroy(&p.system));
  GIPSI_PETSC(MatDuplicate(p.stiffness, MAT_DO_NOT_COPY_VALUES, &p.system));

  GIPSI_PETSC(VecDestroy(&p.v));
  p.v = MakeGhostedNodeVec(part_, comm_);
  GIPSI_PETSC(VecDestroy(&p.rhs));
  GIPSI_PETSC(VecDestroy(&p.work));
  GIPSI_PETSC(VecDestroy(&p.lumped));
  GIPSI_PETSC(VecDuplicate(p.v, &p.rhs));
  GIPSI_PETSC(VecDuplicate(p.v, &p.work));
  GIPSI_PETSC(VecDuplicate(p.v, &p.lumped));
  GIPSI_PETSC(VecSet(p.lumped, 0.0));
  std::vector<PetscInt> all(part_.global.begin(), part_.global.end());
  GIPSI_PETSC(VecSetValues(p.lumped, static_cast<PetscInt>(all.size()), all.data(),
                           ops.lumped_mass.data(), ADD_VALUES));
  GIPSI_PETSC(VecAssemblyBegin(p.lumped));
  GIPSI_PETSC(VecAssemblyEnd(p.lumped));

  GIPSI_PETSC(KSPDestroy(&p.ksp));
  GIPSI_PETSC(KSPCreate(comm_, &p.ksp));
  GIPSI_PETSC(KSPSetOptionsPrefix(p.ksp, "ep_"));
  const LinearSolverOptions& linear = params_.linear;
  GIPSI_PETSC(KSPSetType(p.ksp, linear.type == "cg" ? KSPCG : KSPPREONLY));
  PC pc = nullptr;
  GIPSI_PETSC(KSPGetPC(p.ksp, &pc));
  if (linear.type != "cg") {
    GIPSI_PETSC(PCSetType(pc, PCCHOLESKY));  // a direct solve: MUMPS across ranks
    if (part_.size > 1) GIPSI_PETSC(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  } else if (linear.preconditioner == "amg") {
    GIPSI_PETSC(PCSetType(pc, PCGAMG));
  } else if (linear.preconditioner == "hypre") {
    GIPSI_PETSC(PCSetType(pc, PCHYPRE));
  } else if (linear.preconditioner == "none") {
    GIPSI_PETSC(PCSetType(pc, PCNONE));
  } else {
    GIPSI_PETSC(PCSetType(pc, PCJACOBI));
  }
  GIPSI_PETSC(KSPSetTolerances(p.ksp, linear.tolerance, 1e-50, PETSC_DEFAULT,
                               static_cast<PetscInt>(linear.max_iterations)));
  if (linear.type == "cg") GIPSI_PETSC(KSPSetNormType(p.ksp, KSP_NORM_UNPRECONDITIONED));
  GIPSI_PETSC(KSPSetInitialGuessNonzero(p.ksp, linear.type == "cg" ? PETSC_TRUE : PETSC_FALSE));
  GIPSI_PETSC(KSPSetFromOptions(p.ksp));
  p.system_dt = -1;
  // The base class gets this rank's (partial) lumped mass: the voltage integral is its sum over
  // the ranks. Its K and M are not used (SolveDiffusion is this class's), so none are kept.
  SetDiffusionOperator(SparseMatrix(), std::move(ops.lumped_mass), SparseMatrix());
}

std::string DistributedMonodomain::solver_name() const {
  KSPType type = nullptr;
  PCType pc_type = nullptr;
  PC pc = nullptr;
  KSPGetType(petsc_->ksp, &type);
  KSPGetPC(petsc_->ksp, &pc);
  PCGetType(pc, &pc_type);
  return fmt::format("{} + {}", type != nullptr ? type : "?", pc_type != nullptr ? pc_type : "?");
}

StepStatus DistributedMonodomain::SolveDiffusion(double dt_ms, double* v, int& iterations,
                                                 std::string& detail) {
  Petsc& p = *petsc_;
  const double theta = params_.theta;
  if (dt_ms != p.system_dt) {
    // M + θΔt K (or the lumped M on the diagonal), on the assembled matrices.
    GIPSI_PETSC(MatCopy(p.stiffness, p.system, SAME_NONZERO_PATTERN));
    GIPSI_PETSC(MatScale(p.system, theta * dt_ms));
    if (params_.lumped_mass) {
      GIPSI_PETSC(MatDiagonalSet(p.system, p.lumped, ADD_VALUES));
    } else {
      GIPSI_PETSC(MatAXPY(p.system, 1.0, p.mass, SAME_NONZERO_PATTERN));
    }
    GIPSI_PETSC(KSPSetOperators(p.ksp, p.system, p.system));
    p.system_dt = dt_ms;
  }
  // V into the ghosted vector's local form (owned, then shared entries).
  const auto local = static_cast<std::size_t>(part_.num_local());
  Vec v_local = nullptr;
  PetscScalar* array = nullptr;
  GIPSI_PETSC(VecGhostGetLocalForm(p.v, &v_local));
  GIPSI_PETSC(VecGetArray(v_local, &array));
  std::copy(v, v + local, array);
  GIPSI_PETSC(VecRestoreArray(v_local, &array));
  GIPSI_PETSC(VecGhostRestoreLocalForm(p.v, &v_local));
  if (params_.lumped_mass) {
    GIPSI_PETSC(VecPointwiseMult(p.rhs, p.lumped, p.v));
  } else {
    GIPSI_PETSC(MatMult(p.mass, p.v, p.rhs));
  }
  if (theta < 1) {
    GIPSI_PETSC(MatMult(p.stiffness, p.v, p.work));
    GIPSI_PETSC(VecAXPY(p.rhs, -(1 - theta) * dt_ms, p.work));
  }
  GIPSI_PETSC(KSPSolve(p.ksp, p.rhs, p.v));
  PetscInt its = 0;
  KSPConvergedReason reason = KSP_CONVERGED_ITERATING;
  GIPSI_PETSC(KSPGetIterationNumber(p.ksp, &its));
  GIPSI_PETSC(KSPGetConvergedReason(p.ksp, &reason));
  iterations = static_cast<int>(its);
  if (reason < 0) {
    PetscReal residual = 0, rhs_norm = 0;
    GIPSI_PETSC(KSPGetResidualNorm(p.ksp, &residual));
    GIPSI_PETSC(VecNorm(p.rhs, NORM_2, &rhs_norm));
    const double relative = rhs_norm > 0 ? residual / rhs_norm : residual;
    detail = fmt::format(
        "PETSc {} stopped with {} after {} iterations at a relative residual of "
        "{:.3g} (tolerance {:.3g})",
        solver_name(), KSPConvergedReasons[reason], its, relative, params_.linear.tolerance);
    return StepStatus::Failed("the diffusion solve did not converge", -1, relative);
  }
  GIPSI_PETSC(VecGhostUpdateBegin(p.v, INSERT_VALUES, SCATTER_FORWARD));
  GIPSI_PETSC(VecGhostUpdateEnd(p.v, INSERT_VALUES, SCATTER_FORWARD));
  GIPSI_PETSC(VecGhostGetLocalForm(p.v, &v_local));
  GIPSI_PETSC(VecGetArray(v_local, &array));
  std::copy(array, array + local, v);
  GIPSI_PETSC(VecRestoreArray(v_local, &array));
  GIPSI_PETSC(VecGhostRestoreLocalForm(p.v, &v_local));
  return StepStatus::Ok();
}

StepStatus DistributedMonodomain::DoStep(double t, double dt) {
  StepStatus status = EpTissue::DoStep(t, dt);
  struct {
    int severity;
    int rank;
  } mine{Severity(status.code), part_.rank}, worst{0, 0};
  MPI_Allreduce(&mine, &worst, 1, MPI_2INT, MPI_MAXLOC, comm_);
  if (worst.severity == 0 || !status.ok()) {
    // The failing rank names the node of the whole mesh.
    if (!status.ok() && status.item >= 0 && status.item < part_.num_local())
      status.item = part_.whole_node[static_cast<std::size_t>(status.item)];
    return status;
  }
  switch (worst.severity) {
    case 3:
      return StepStatus::Diverged("another rank's part of the object diverged", worst.rank);
    case 2:
      return StepStatus::Failed("another rank's part of the object failed", worst.rank);
    default:
      return StepStatus::Stopped();
  }
}

void DistributedMonodomain::DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const {
  if (id == f_activated_) {
    double counts[2] = {0, static_cast<double>(part_.num_owned)};
    for (Index i = 0; i < part_.num_owned; ++i) counts[0] += activation_time()[i] >= 0 ? 1 : 0;
    MPI_Allreduce(MPI_IN_PLACE, counts, 2, MPI_DOUBLE, MPI_SUM, comm_);
    out(0, 0) = counts[1] > 0 ? counts[0] / counts[1] : 0.0;
  } else if (id == f_fibre_) {
    out = fibres_;
  } else if (id == f_integral_) {
    double integral = VoltageIntegral();  // this rank's tets
    MPI_Allreduce(MPI_IN_PLACE, &integral, 1, MPI_DOUBLE, MPI_SUM, comm_);
    out(0, 0) = 1e-9 * integral;  // mV·mm³ → mV·m³
  } else {
    EpTissue::DoReadField(id, out);  // per local node, or the same on every rank
  }
}

}  // namespace gipsi
