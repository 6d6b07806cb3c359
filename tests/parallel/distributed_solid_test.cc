// FemSolid split over the ranks of MPI_COMM_WORLD (parallel/distributed_solid.h) behind a
// WholeDomainView, against the serial object on the same mesh with the same conditions. Runs
// under `mpiexec -np 2` and `-np 4 --oversubscribe` (tests/CMakeLists.txt); every test is
// collective.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mpi.h>
#include <spdlog/sinks/ostream_sink.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/base/log.h"
#include "gipsi/core/cavity_law.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/geometry/region.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/solid_laws.h"
#include "gipsi/numerics/ode.h"
#include "gipsi/parallel/distributed_solid.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/parallel_session.h"
#include "gipsi/parallel/whole_domain_view.h"
#include "parallel/cantilever.h"

namespace gipsi {
namespace {

MPI_Comm World() { return ParallelSession::world(); }

using test::CantileverMesh;
using test::CantileverParams;
using test::Clamp;
using ::testing::HasSubstr;

// The serial object, or the view on this rank's part, on the same whole mesh; stepped by
// `integrator` through the ODE contract when one is given.
std::unique_ptr<SimObject> MakeSolid(std::shared_ptr<const Mesh> whole, FemParams params,
                                     bool split,
                                     std::unique_ptr<OdeIntegrator> integrator = nullptr) {
  auto make = [&](std::shared_ptr<const Mesh> mesh) {
    return integrator ? std::make_unique<FemSolid>("solid", std::move(mesh), std::move(params),
                                                   std::move(integrator))
                      : std::make_unique<FemSolid>("solid", std::move(mesh), std::move(params));
  };
  if (!split) return make(whole);
  auto distribution = std::make_shared<DistributedSolid>(whole, World());
  params.distribution = distribution;
  const MeshPart& part = distribution->part();
  return std::make_unique<WholeDomainView>(
      make(part.mesh), part, whole, World(),
      WholeDomainView::BoundaryMap{distribution->whole_boundary_vertex(),
                                   distribution->whole_boundary_face()});
}

Eigen::MatrixXd Read(const SimObject& object, const std::string& field) {
  const FieldId id = object.FindField(field);
  Eigen::MatrixXd out(object.field_info(id).components, object.FieldCount(id));
  object.ReadField(id, out);
  return out;
}

// 40 steps of 5 ms: through the first swing, with steps where the first Newton correction
// raises the residual (accepted by the monotonicity test). Both runs solve every step's
// equations to a relative residual of 1e-11 (Newton and CG), so their positions differ by the
// conditioning of the step's tangent (mass-dominated: ~1e2) times that: 1e-9 of the sag bounds
// it with a factor 10 to spare. The split run uses GAMG with the rigid-body modes (the default
// of split runs), the serial one block Gauss-Seidel: their solutions agree only as solutions.
TEST(DistributedSolid, CantileverSwingsAsTheSerialObject) {
  const auto whole = CantileverMesh();
  auto serial = MakeSolid(whole, CantileverParams("sgs"), false);
  auto split = MakeSolid(whole, CantileverParams("amg"), true);
  Clamp(*serial);
  Clamp(*split);
  for (int step = 0; step < 40; ++step) {
    ASSERT_TRUE(serial->Step(0.005).ok());
    ASSERT_TRUE(split->Step(0.005).ok());
  }
  const Eigen::MatrixXd u = Read(*serial, "displacement");
  const Eigen::MatrixXd u_split = Read(*split, "displacement");
  const double sag = u.cwiseAbs().maxCoeff();
  EXPECT_GT(sag, 0.02);
  EXPECT_LE((u - u_split).cwiseAbs().maxCoeff(), 1e-9 * sag);
  // Reductions over the ranks: energies, and the clamp's reaction (a boundary field read from
  // the owners of its vertices).
  for (const char* energy : {"kinetic_energy", "strain_energy"}) {
    const double a = Read(*serial, energy)(0, 0), b = Read(*split, energy)(0, 0);
    EXPECT_NEAR(b, a, 1e-8 * std::abs(a)) << energy;
  }
  const Eigen::Vector3d reaction = Read(*serial, "reaction_force").rowwise().sum();
  const Eigen::Vector3d reaction_split = Read(*split, "reaction_force").rowwise().sum();
  EXPECT_GT(reaction.norm(), 0.01);  // of the order of the weight, 0.098 N
  EXPECT_LE((reaction - reaction_split).norm(), 1e-7 * reaction.norm());
  EXPECT_NEAR(Read(*split, "volume")(0, 0), Read(*serial, "volume")(0, 0), 1e-12);
}

// Every preconditioner a split run offers besides GAMG solves the steps the serial object
// solves (same bound as above, over 10 steps). CG with 3×3 point-block Jacobi once met an
// indefinite preconditioner at the first solve on more than one rank (PETSc 3.18's PCPBJACOBI
// read a block size the COO preallocation had left at 1).
TEST(DistributedSolid, EveryPreconditionerSwingsAsTheSerialObject) {
  const auto whole = CantileverMesh();
  auto serial = MakeSolid(whole, CantileverParams("sgs"), false);
  Clamp(*serial);
  for (int step = 0; step < 10; ++step) ASSERT_TRUE(serial->Step(0.005).ok());
  const Eigen::MatrixXd u = Read(*serial, "displacement");
  const double sag = u.cwiseAbs().maxCoeff();
  EXPECT_GT(sag, 1e-3);
  for (const char* preconditioner : {"jacobi", "sgs", "hypre", "none"}) {
    auto split = MakeSolid(whole, CantileverParams(preconditioner), true);
    Clamp(*split);
    for (int step = 0; step < 10; ++step) ASSERT_TRUE(split->Step(0.005).ok()) << preconditioner;
    EXPECT_LE((u - Read(*split, "displacement")).cwiseAbs().maxCoeff(), 1e-9 * sag)
        << preconditioner;
  }
}

// GAMG says when it coarsens a mesh poorly: on a box cut into 5 tets per cell its levels hold
// more than 3 times the tangent's nonzeros (4.6 at 60 × 6 × 6 cells, docs/performance.md), on
// the same box cut into 6 about 1.2. Said once per object, at its first hierarchy.
TEST(DistributedSolid, GamgSaysWhenItCoarsensAMeshPoorly) {
  for (const HexSplit split : {HexSplit::kFive, HexSplit::kSix}) {
    const auto box =
        std::make_shared<Mesh>(MakeTetBox(Vec3::Zero(), Vec3(0.1, 0.01, 0.01), {60, 6, 6}, split));
    std::ostringstream captured;
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(captured);
    Log().sinks().push_back(sink);
    auto solid = MakeSolid(box, CantileverParams("amg"), true);
    Clamp(*solid);
    for (int step = 0; step < 2; ++step) EXPECT_TRUE(solid->Step(0.005).ok());
    Log().sinks().pop_back();
    const std::string text = captured.str();
    const auto said = static_cast<int>(std::count(text.begin(), text.end(), '\n'));
    if (split == HexSplit::kFive) {
      EXPECT_THAT(text, HasSubstr("a split FemSolid: GAMG's levels hold 4."));
      EXPECT_THAT(text, HasSubstr("\"preconditioner\": \"hypre\""));
      EXPECT_EQ(said, 1) << text;  // once, though Newton builds several hierarchies
    } else {
      EXPECT_EQ(text.find("GAMG"), std::string::npos) << text;
    }
  }
}

// A cantilever made block by block, which no rank holds whole: its part's boundary, found by
// exchanges between the ranks, is the whole mesh's boundary restricted to the part (faces,
// their orientation and order, every local node on it as a vertex, and their numbers on the
// whole boundary), and a FemSolid on it,
// clamped on its own boundary, swings as the one split from the whole mesh.
TEST(DistributedSolid, APartMadeInBlocksFindsTheWholeBoundaryAndSwingsAlike) {
  const auto whole = CantileverMesh();
  auto from_whole = std::make_shared<DistributedSolid>(whole, World());
  auto from_blocks = std::make_shared<DistributedSolid>(
      PartitionMeshBlocks(
          MakeTetBoxBlock(Vec3::Zero(), Vec3(0.1, 0.01, 0.01), {20, 2, 2}, HexSplit::kSix,
                          ParallelSession::rank(World()), ParallelSession::size(World())),
          World()),
      World());
  ASSERT_EQ(from_blocks->part().whole_node, from_whole->part().whole_node);
  ASSERT_EQ(from_blocks->part().whole_tet, from_whole->part().whole_tet);
  const BoundarySurface &a = from_whole->boundary(), &b = from_blocks->boundary();
  EXPECT_EQ(b.vertex_to_node, a.vertex_to_node);
  EXPECT_EQ(b.triangles, a.triangles);
  EXPECT_EQ(b.face_to_tet, a.face_to_tet);
  EXPECT_GT(b.num_triangles(), 0);
  // Where its vertices and faces are on the whole boundary, numbered by ranking at the block
  // ranks: what the whole mesh's boundary says.
  EXPECT_EQ(from_blocks->whole_boundary_vertex(), from_whole->whole_boundary_vertex());
  EXPECT_EQ(from_blocks->whole_boundary_face(), from_whole->whole_boundary_face());
  const BoundarySurface whole_boundary = MakeBoundary(*whole);
  EXPECT_EQ(from_blocks->whole_boundary_vertices(), whole_boundary.num_vertices());
  EXPECT_EQ(from_blocks->whole_boundary_faces(), whole_boundary.num_triangles());

  FemParams params_a = CantileverParams("amg"), params_b = CantileverParams("amg");
  params_a.distribution = from_whole;
  params_b.distribution = from_blocks;
  FemSolid solid_a("a", from_whole->part().mesh, std::move(params_a));
  FemSolid solid_b("b", from_blocks->part().mesh, std::move(params_b));
  Clamp(solid_a);
  Clamp(solid_b);
  for (int step = 0; step < 20; ++step) {
    ASSERT_TRUE(solid_a.Step(0.005).ok());
    ASSERT_TRUE(solid_b.Step(0.005).ok());
  }
  const Eigen::MatrixXd u_a = Read(solid_a, "displacement"), u_b = Read(solid_b, "displacement");
  double sag = u_a.cwiseAbs().maxCoeff();  // the largest over the ranks: the tip's
  MPI_Allreduce(MPI_IN_PLACE, &sag, 1, MPI_DOUBLE, MPI_MAX, World());
  EXPECT_GT(sag, 0.01);
  // The same arithmetic; on 4 ranks two runs of the same split differ by up to 1e-17 m (the
  // order in which shared nodes' sums arrive), so the bound is the split-vs-serial one.
  EXPECT_LE((u_b - u_a).cwiseAbs().maxCoeff(), 1e-9 * sag);
}

// The view of a FemSolid made in blocks keeps its part's boundary conditions only: a region
// selects on each part exactly the part's vertices and faces that the serial selection on the
// whole mesh has (face groups, faces whose three vertices a box or a half-space selects, node
// ids, every face), a vertex on a cut on every part that holds it, and counts the whole
// selection's items once; and each rank's own boundary vertices of a region (what probes
// reduce) make the whole selection once over the ranks.
TEST(DistributedSolid, APartOnlyViewSelectsTheWholeBoundarysItems) {
  const auto whole = CantileverMesh();
  const BoundarySurface whole_boundary = MakeBoundary(*whole);
  auto distribution = std::make_shared<DistributedSolid>(
      PartitionMeshBlocks(
          MakeTetBoxBlock(Vec3::Zero(), Vec3(0.1, 0.01, 0.01), {20, 2, 2}, HexSplit::kSix,
                          ParallelSession::rank(World()), ParallelSession::size(World())),
          World()),
      World());
  FemParams params = CantileverParams("amg");
  params.distribution = distribution;
  const MeshPart& part = distribution->part();
  WholeDomainView view(
      std::make_unique<FemSolid>("solid", part.mesh, std::move(params)), part, World(),
      WholeDomainView::BoundaryMap{
          distribution->whole_boundary_vertex(), distribution->whole_boundary_face(),
          distribution->whole_boundary_vertices(), distribution->whole_boundary_faces()});
  ASSERT_FALSE(view.holds_whole_domain());
  EXPECT_EQ(view.boundary_conditions().num_vertices(), view.boundary().num_vertices());
  EXPECT_EQ(view.boundary_conditions().num_faces(), view.boundary().num_triangles());
  const std::vector<int>& whole_vertex = distribution->whole_boundary_vertex();
  const std::vector<int>& whole_face = distribution->whole_boundary_face();
  const std::vector<Region> regions = {AllRegion{},
                                       GroupRegion{"xmax"},
                                       GroupRegion{"zmax"},
                                       BoxRegion{Vec3(0.03, -1, -1), Vec3(0.07, 0.0001, 1)},
                                       HalfSpaceRegion{Vec3(0.05, 0, 0), Vec3(1, 0, 0)},
                                       NodeIdsRegion{{0, 20, 21, 40, 62, 100}}};
  for (std::size_t k = 0; k < regions.size(); ++k) {
    const Region& region = regions[k];
    const std::vector<int> vertices = SelectBoundaryVertices(region, *whole, whole_boundary);
    const std::vector<int> faces = SelectBoundaryFaces(region, *whole, whole_boundary);
    EXPECT_FALSE(vertices.empty()) << "region " << k;
    for (const bool on_faces : {false, true}) {
      const std::vector<int>& serial = on_faces ? faces : vertices;
      const std::vector<int>& whole_of = on_faces ? whole_face : whole_vertex;
      const PartitionedObject::ConditionItems selected =
          view.SelectConditionItems(region, on_faces);
      EXPECT_EQ(selected.whole_count, static_cast<std::int64_t>(serial.size())) << "region " << k;
      std::vector<int> expected;  // the part's items the serial selection has
      for (std::size_t i = 0; i < whole_of.size(); ++i)
        if (std::binary_search(serial.begin(), serial.end(), whole_of[i]))
          expected.push_back(static_cast<int>(i));
      EXPECT_EQ(selected.items, expected) << "region " << k << (on_faces ? " faces" : " vertices");
    }
    std::vector<int> owned;
    for (const int v : view.SelectOwnedBoundaryVertices(region)) {
      EXPECT_LT(view.boundary().vertex_to_node[static_cast<std::size_t>(v)], part.num_owned);
      owned.push_back(distribution->whole_boundary_vertex()[static_cast<std::size_t>(v)]);
    }
    const int count = static_cast<int>(owned.size());
    std::vector<int> counts(static_cast<std::size_t>(ParallelSession::size(World())));
    MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, World());
    std::vector<int> offsets(counts.size(), 0);
    for (std::size_t r = 1; r < counts.size(); ++r) offsets[r] = offsets[r - 1] + counts[r - 1];
    std::vector<int> all(static_cast<std::size_t>(offsets.back() + counts.back()));
    MPI_Allgatherv(owned.data(), count, MPI_INT, all.data(), counts.data(), offsets.data(), MPI_INT,
                   World());
    std::sort(all.begin(), all.end());
    EXPECT_EQ(all, vertices) << "region " << k;  // each once: no repeats
  }
  // A group no part has is refused on every rank.
  EXPECT_THROW((void)view.SelectConditionItems(GroupRegion{"no_such_group"}, false), InputError);
}

// The same release with the Newmark scheme (average acceleration), which starts from the
// acceleration of M a₀ = f_ext − f_int − C v₀: the split run sums the ranks' partial forces and
// masses (lumped), or solves with the ranks' partial mass matrices summed (consistent). Same
// bound as above; a wrong a₀ (a partial sum at the shared nodes) would show in the first step.
TEST(DistributedSolid, CantileverSwingsAsTheSerialObjectWithNewmark) {
  const auto whole = CantileverMesh();
  for (bool lumped : {false, true}) {
    FemParams serial_params = CantileverParams("sgs"), split_params = CantileverParams("amg");
    for (FemParams* p : {&serial_params, &split_params}) {
      p->scheme = ImplicitSchemeKind::kNewmark;
      p->lumped_mass = lumped;
    }
    auto serial = MakeSolid(whole, serial_params, false);
    auto split = MakeSolid(whole, split_params, true);
    Clamp(*serial);
    Clamp(*split);
    for (int step = 0; step < 40; ++step) {
      ASSERT_TRUE(serial->Step(0.005).ok()) << "lumped " << lumped;
      ASSERT_TRUE(split->Step(0.005).ok()) << "lumped " << lumped;
    }
    const Eigen::MatrixXd u = Read(*serial, "displacement");
    const double sag = u.cwiseAbs().maxCoeff();
    EXPECT_GT(sag, 0.02) << "lumped " << lumped;
    EXPECT_LE((u - Read(*split, "displacement")).cwiseAbs().maxCoeff(), 1e-9 * sag)
        << "lumped " << lumped;
    const Eigen::MatrixXd v = Read(*serial, "velocity");
    EXPECT_LE((v - Read(*split, "velocity")).cwiseAbs().maxCoeff(), 1e-9 * v.cwiseAbs().maxCoeff())
        << "lumped " << lumped;
  }
}

// The release integrated explicitly (scenes/cantilever_explicit.json: RK4 through the ODE
// contract, lumped mass, 0.1 ms): every stage's forces and the lumped masses are summed at the
// shared nodes, so the split run computes the serial run's accelerations up to the order of
// the sums (rounding). Over 500 steps (50 ms, into the first swing) positions, velocities and
// the clamp's reaction agree within 1e-9 of their scale. An implicit ODE integrator (its
// matrix-free Newton is serial) is refused.
TEST(DistributedSolid, CantileverSwingsAsTheSerialObjectWithRk4) {
  const auto whole = CantileverMesh();
  FemParams params = CantileverParams("sgs");
  params.lumped_mass = true;
  auto serial = MakeSolid(whole, params, false, std::make_unique<RungeKutta4>());
  auto split = MakeSolid(whole, params, true, std::make_unique<RungeKutta4>());
  Clamp(*serial);
  Clamp(*split);
  for (int step = 0; step < 500; ++step) {
    ASSERT_TRUE(serial->Step(1e-4).ok());
    ASSERT_TRUE(split->Step(1e-4).ok());
  }
  for (const char* field : {"displacement", "velocity", "reaction_force"}) {
    const Eigen::MatrixXd a = Read(*serial, field), b = Read(*split, field);
    EXPECT_GT(a.cwiseAbs().maxCoeff(), 0) << field;
    EXPECT_LE((a - b).cwiseAbs().maxCoeff(), 1e-9 * a.cwiseAbs().maxCoeff()) << field;
  }
  const double k = Read(*serial, "kinetic_energy")(0, 0);
  EXPECT_NEAR(Read(*split, "kinetic_energy")(0, 0), k, 1e-9 * k);
  EXPECT_THROW(MakeSolid(whole, params, true, std::make_unique<BackwardEulerOde>()), InputError);
}

// Land et al.'s benchmark ventricle (2015, problem 2; scenes/lv_inflation.json) on a coarse
// mesh (3 mm), isotropic Guccione, C = 10 kPa, κ = 1000 C, no gravity.
std::shared_ptr<const Mesh> Ventricle() {
  EllipsoidShellSpec spec;
  spec.endo_short = 0.007;
  spec.endo_long = 0.017;
  spec.epi_short = 0.010;
  spec.epi_long = 0.020;
  spec.base_z = 0.005;
  spec.mesh_size = 0.003;
  return std::make_shared<Mesh>(MakeEllipsoidShell(spec));
}

FemParams VentricleParams() {
  FemParams p;
  GuccioneParams law{.C = 1e4, .bf = 1, .bt = 1, .bfs = 1, .bulk_modulus = 1e7};
  p.material = std::make_shared<GuccioneSolid>(law);
  p.fibre = Vec3::UnitZ();
  p.gravity = Vec3::Zero();
  return p;
}

// Holds the base (z = 5 mm) of an object on Ventricle().
void HoldBase(SimObject& solid) {
  const BoundarySurface& b = solid.boundary();
  for (Index v = 0; v < b.num_vertices(); ++v)
    if (solid.domain().nodes(2, b.vertex_to_node[static_cast<std::size_t>(v)]) > 0.005 - 1e-9)
      solid.boundary_conditions().Fix(v);
}

// The ventricle inflated to 10 kPa on the endocardium in 10 load increments, static. Both runs
// factorise with CHOLMOD until the tangent turns indefinite (half-way), then with an LDLᵀ (the
// serial object's own, MUMPS's in the split run's redundant solve): direct solves, Newton to
// 1e-10, so the apex agrees to 1e-8 of its 3 mm drop.
TEST(DistributedSolid, InflatedVentricleAsTheSerialObject) {
  const auto whole = Ventricle();
  FemParams p = VentricleParams();
  p.scheme = ImplicitSchemeKind::kStatic;
  p.load_steps = 10;
  p.newton.max_iterations = 50;
  p.newton.tolerance = 1e-10;
  p.linear_solver.type = "cholmod";
  std::unique_ptr<SimObject> solids[2] = {MakeSolid(whole, p, false), MakeSolid(whole, p, true)};
  for (auto& solid : solids) {
    HoldBase(*solid);
    const BoundarySurface& b = solid->boundary();
    const Points& x = solid->domain().nodes;
    // Endocardial faces: their centroid nearer the inner ellipsoid than the outer one.
    for (Index f = 0; f < b.num_triangles(); ++f) {
      Vec3 c = Vec3::Zero();
      for (int a = 0; a < 3; ++a)
        c += x.col(b.vertex_to_node[static_cast<std::size_t>(b.triangles(a, f))]) / 3;
      const double endo = std::hypot(std::hypot(c.x(), c.y()) / 0.007, c.z() / 0.017);
      if (endo < 1.15 && c.z() < 0.005 - 1e-9) solid->boundary_conditions().SetPressure(f, 1e4);
    }
    ASSERT_TRUE(solid->Step(1.0).ok()) << solid->failure_detail();
  }
  const Eigen::MatrixXd u = Read(*solids[0], "displacement");
  const Eigen::MatrixXd u_split = Read(*solids[1], "displacement");
  const double drop = u.row(2).cwiseAbs().maxCoeff();
  EXPECT_GT(drop, 0.002);
  EXPECT_LE((u - u_split).cwiseAbs().maxCoeff(), 1e-8 * drop);
}

// Blood that fills the cavity at a set rate through a compliant inlet: V_b(p) = V₀ + q (t + Δt)
// − c p (non-increasing in p, as a CavityLaw must be).
class FillingLaw final : public CavityLaw {
 public:
  FillingLaw(double v0, double rate, double compliance) : v0_(v0), q_(rate), c_(compliance) {}
  bool EndVolume(double t, double dt, double p, double& volume) override {
    volume = v0_ + q_ * (t + dt) - c_ * p;
    return true;
  }

 private:
  double v0_, q_, c_;
};

// The ventricle above with its endocardial cavity coupled to blood (the heart's coupling: the
// pressure a bordered Newton unknown, the cavity volume and its gradient over the whole
// endocardium, whose vertices each rank gathers), filled by 2 mL in 0.1 s (backward Euler):
// the split run gives the serial run's pressure, volume and displacements (direct solves,
// Newton converged to 1e-10 on both), so within 1e-8 relative.
TEST(DistributedSolid, CoupledCavityFillsAsTheSerialObject) {
  const auto whole = Ventricle();
  FemParams p = VentricleParams();
  p.newton.tolerance = 1e-10;
  p.linear_solver.type = "cholmod";
  p.cavities = {{"lv", GroupRegion{"endo"}}};
  std::unique_ptr<SimObject> solids[2] = {MakeSolid(whole, p, false), MakeSolid(whole, p, true)};
  const double v0 = Read(*solids[0], "lv_volume")(0, 0);
  EXPECT_NEAR(Read(*solids[1], "lv_volume")(0, 0), v0, 1e-15);
  FillingLaw blood(v0, 2e-6 / 0.1, 1e-11);
  for (auto& solid : solids) {
    HoldBase(*solid);
    CavityWallOf(*solid).AttachCavityLaw("lv", &blood);
    for (int step = 0; step < 10; ++step) {
      solid->SetTime(0.01 * step);
      ASSERT_TRUE(solid->Step(0.01).ok()) << solid->failure_detail();
    }
  }
  const double pressure = Read(*solids[0], "lv_pressure")(0, 0);
  EXPECT_GT(pressure, 100.0);  // Pa: the wall resists the filling
  EXPECT_NEAR(Read(*solids[1], "lv_pressure")(0, 0), pressure, 1e-8 * pressure);
  const double volume = Read(*solids[0], "lv_volume")(0, 0);
  EXPECT_NEAR(volume, v0 + 2e-6 - 1e-11 * pressure, 1e-12);  // what the blood fills
  EXPECT_NEAR(Read(*solids[1], "lv_volume")(0, 0), volume, 1e-8 * volume);
  const Eigen::MatrixXd u = Read(*solids[0], "displacement");
  EXPECT_LE((u - Read(*solids[1], "displacement")).cwiseAbs().maxCoeff(),
            1e-8 * u.cwiseAbs().maxCoeff());
}

// The ventricle made in blocks, which no rank holds whole, with the same cavity: its faces,
// selected on the parts and gathered, are the whole mesh's selection (a face group, and the
// faces whose vertices a box selects), in the whole boundary's order and vertex order; the
// part's FemSolid encloses the volume of the solid split from the whole mesh (the same parts,
// cavity surface and sums: measured equal bits) and, coupled to the filling blood, fills as it
// does: pressure, volume and displacements within the split-vs-serial bound of 1e-8 above. A
// cavity whose region selects no face is refused on every rank with the serial message.
TEST(DistributedSolid, ACavityMadeInBlocksIsTheWholeMeshsCavity) {
  const auto whole = Ventricle();
  const BoundarySurface whole_boundary = MakeBoundary(*whole);
  auto from_whole = std::make_shared<DistributedSolid>(whole, World());
  auto from_blocks = std::make_shared<DistributedSolid>(
      PartitionMeshBlocks(
          BlockOfMesh(*whole, ParallelSession::rank(World()), ParallelSession::size(World())),
          World()),
      World());
  ASSERT_FALSE(from_blocks->has_whole_mesh());
  ASSERT_EQ(from_blocks->part().whole_tet, from_whole->part().whole_tet);
  for (const Region& region :
       {Region{GroupRegion{"endo"}}, Region{BoxRegion{Vec3(-1, -1, -1), Vec3(1, 0.002, 0)}}}) {
    const std::vector<int> expected = SelectBoundaryFaces(region, *whole, whole_boundary);
    ASSERT_FALSE(expected.empty());
    const WholeFaceSelection got = from_blocks->SelectWholeFaces(region);
    EXPECT_EQ(got.faces, expected);
    ASSERT_EQ(got.surface.num_triangles(), static_cast<Index>(expected.size()));
    for (std::size_t k = 0; k < expected.size(); ++k)
      for (int a = 0; a < 3; ++a)
        ASSERT_EQ(got.surface.vertex_to_node[static_cast<std::size_t>(
                      got.surface.triangles(a, static_cast<Index>(k)))],
                  whole_boundary.vertex_to_node[static_cast<std::size_t>(
                      whole_boundary.triangles(a, expected[k]))]);
  }
  FemParams p = VentricleParams();
  p.newton.tolerance = 1e-10;
  p.linear_solver.type = "cholmod";
  p.cavities = {{"lv", GroupRegion{"endo"}}};
  FemParams pa = p, pb = p;
  pa.distribution = from_whole;
  pb.distribution = from_blocks;
  FemSolid a("a", from_whole->part().mesh, std::move(pa));
  FemSolid b("b", from_blocks->part().mesh, std::move(pb));
  const double v0 = Read(a, "lv_volume")(0, 0);
  EXPECT_EQ(Read(b, "lv_volume")(0, 0), v0);
  FillingLaw blood_a(v0, 2e-6 / 0.1, 1e-11), blood_b(v0, 2e-6 / 0.1, 1e-11);
  a.AttachCavityLaw("lv", &blood_a);
  b.AttachCavityLaw("lv", &blood_b);
  HoldBase(a);
  HoldBase(b);
  for (int step = 0; step < 10; ++step) {
    for (FemSolid* solid : {&a, &b}) {
      solid->SetTime(0.01 * step);
      ASSERT_TRUE(solid->Step(0.01).ok()) << solid->failure_detail();
    }
  }
  const double pressure = Read(a, "lv_pressure")(0, 0);
  EXPECT_GT(pressure, 100.0);
  EXPECT_NEAR(Read(b, "lv_pressure")(0, 0), pressure, 1e-8 * pressure);
  const double volume = Read(a, "lv_volume")(0, 0);
  EXPECT_NEAR(Read(b, "lv_volume")(0, 0), volume, 1e-8 * volume);
  const Eigen::MatrixXd u = Read(a, "displacement");
  double scale = u.cwiseAbs().maxCoeff();
  MPI_Allreduce(MPI_IN_PLACE, &scale, 1, MPI_DOUBLE, MPI_MAX, World());
  EXPECT_LE((u - Read(b, "displacement")).cwiseAbs().maxCoeff(), 1e-8 * scale);

  FemParams none = VentricleParams();
  none.cavities = {{"lv", BoxRegion{Vec3::Constant(1), Vec3::Constant(2)}}};
  none.distribution = from_blocks;
  EXPECT_THAT([&] { FemSolid("c", from_blocks->part().mesh, std::move(none)); },
              ::testing::ThrowsMessage<InputError>(
                  ::testing::HasSubstr("cavity 'lv' selects no boundary face")));
}

// A load that inverts elements: the step fails on every rank alike (the admissibility verdict
// is a reduction), naming the same element, and leaves every part at its start.
TEST(DistributedSolid, AFailedStepFailsEveryRankAlike) {
  FemParams p = CantileverParams("amg");
  p.scheme = ImplicitSchemeKind::kStatic;
  p.gravity = Vec3(0, 0, -1e5);
  p.max_bisections = 0;
  p.newton.max_iterations = 5;
  auto split = MakeSolid(CantileverMesh(), p, true);
  Clamp(*split);
  const StepStatus status = split->Step(1.0);
  EXPECT_EQ(status.code, StepStatus::Code::kFailed);
  const std::int64_t mine[2] = {static_cast<std::int64_t>(status.code), status.item};
  std::int64_t low[2] = {0, 0}, high[2] = {0, 0};
  MPI_Allreduce(mine, low, 2, MPI_INT64_T, MPI_MIN, World());
  MPI_Allreduce(mine, high, 2, MPI_INT64_T, MPI_MAX, World());
  EXPECT_EQ(low[0], high[0]);
  EXPECT_EQ(low[1], high[1]);
  EXPECT_EQ(Read(*split, "displacement").cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace gipsi
