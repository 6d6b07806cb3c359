// The monodomain split over the ranks of MPI_COMM_WORLD (parallel/distributed_monodomain.h),
// against the serial object on the same mesh. Runs under `mpiexec -np 2` and
// `-np 4 --oversubscribe` (tests/CMakeLists.txt); every test is collective.

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>
#include <random>
#include <set>

#include "gipsi/base/error.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/geometry/region.h"
#include "gipsi/models/ep/monodomain.h"
#include "gipsi/models/ep/ten_tusscher_panfilov_2006.h"
#include "gipsi/parallel/distributed_monodomain.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/parallel_session.h"
#include "gipsi/parallel/whole_domain_view.h"

namespace gipsi {
namespace {

MPI_Comm World() { return ParallelSession::world(); }
int Rank() { return ParallelSession::rank(World()); }
int Size() { return ParallelSession::size(World()); }

// The solvers stop at a relative residual of 1e-11 here (the scenes use 1e-8). What an
// iterative solve leaves accumulates over the steps into the activation times: measured on this
// slab against a direct solve, 1e-3 ms at 1e-8 and at most 1.5e-6 ms at 1e-11 (CG + Jacobi,
// GAMG, BoomerAMG; GAMG on 4 ranks the largest). At 1e-11, 1e-5 ms (a thousandth of the time
// step) bounds what any difference between two correct solvers can leave, including a solve
// that takes one iteration more on one side through rounding.
constexpr double kSolverTolerance = 1e-11;
constexpr double kActivationBound = 1e-5;  // ms

// The N-version benchmark slab (Niederer et al. 2011, scenes/slab_ep_0.5mm.json): 20 × 7 × 3 mm
// of ten Tusscher-Panfilov 2006 epicardial cells, fibres along x, σ the harmonic means of the
// intra- and extracellular conductivities, χ 140 /mm, Cm 1 µF/cm², 50,000 µA/cm³ for 2 ms in a
// 1.5 mm cube at the origin (÷ χ Cm = 35.7 µA/µF).
EpTissueParams SlabParams(const std::string& preconditioner, const std::string& type = "cg") {
  EpTissueParams p;
  p.cell = std::make_shared<TenTusscherPanfilov2006>();
  p.sigma_longitudinal = 0.17 * 0.62 / (0.17 + 0.62);
  p.sigma_transverse = 0.019 * 0.24 / (0.019 + 0.24);
  p.fibre = Vec3::UnitX();
  p.surface_to_volume = 1.4e5;
  p.capacitance = 0.01;
  p.linear.type = type;
  p.linear.preconditioner = preconditioner;
  p.linear.tolerance = kSolverTolerance;
  StimulusSpec corner;
  corner.name = "corner";
  corner.region = BoxRegion{Vec3::Constant(-1e-6), Vec3::Constant(0.0015001)};
  corner.amplitude = 50000.0 / (1400.0 * 1.0);
  corner.pulses.duration = 2.0;
  p.stimuli.push_back(corner);
  p.activation_threshold = 0;
  return p;
}

// This rank's part of Slab(cells_per_mm_x2), made block by block (no rank holds it whole).
MeshPart SlabInBlocks(int cells_per_mm_x2) {
  const int n = cells_per_mm_x2;
  return PartitionMeshBlocks(
      MakeTetBoxBlock(Vec3::Zero(), Vec3(0.020, 0.007, 0.003), {20 * n, 7 * n, 3 * n},
                      HexSplit::kSix, Rank(), Size()),
      World());
}

std::shared_ptr<const Mesh> Slab(int cells_per_mm_x2) {
  const int n = cells_per_mm_x2;
  return std::make_shared<Mesh>(
      MakeTetBox(Vec3::Zero(), Vec3(0.020, 0.007, 0.003), {20 * n, 7 * n, 3 * n}));
}

// Probes read a split object's items through its whole-mesh view, each item sent by the rank
// that owns it: the values are the whole field's (ReadField's gather), bitwise, for node and
// element fields, for items in any order and repeated, on every rank.
TEST(WholeDomainView, ReadingItemsGivesTheWholeFieldsColumnsOnEveryRank) {
  const auto whole = Slab(1);
  auto part =
      std::make_unique<DistributedMonodomain>("tissue", *whole, SlabParams("jacobi"), World());
  const MeshPart& mesh_part = part->part();
  WholeDomainView view(std::move(part), mesh_part, whole, World());
  for (int s = 0; s < 300; ++s) ASSERT_TRUE(view.Step(1e-5).ok());  // 3 ms: an upstroke
  const int nodes = static_cast<int>(whole->num_nodes());
  const std::vector<int> items = {nodes - 1, 0, 17, 17, nodes / 2, 3};
  int checked = 0;
  for (const FieldInfo& info : view.fields()) {
    if (info.location == FieldLocation::kGlobal || !info.readable()) continue;
    const FieldId id = view.FindField(info.name);
    Eigen::MatrixXd all(info.components, view.FieldCount(id));
    Eigen::MatrixXd some(info.components, static_cast<Index>(items.size()));
    view.ReadField(id, all);
    view.ReadFieldItems(id, items, some);
    for (std::size_t k = 0; k < items.size(); ++k)
      for (int c = 0; c < info.components; ++c)
        EXPECT_EQ(std::bit_cast<std::uint64_t>(some(c, static_cast<Index>(k))),
                  std::bit_cast<std::uint64_t>(all(c, items[k])))
            << info.name << " item " << items[k];
    ++checked;
  }
  EXPECT_GE(checked, 2);  // V and activation_time at least
}

// A part-only view (no whole mesh on any rank): a whole slab on every rank for reference, and
// the view on the slab made in blocks.
struct PartOnly {
  std::shared_ptr<const Mesh> whole = Slab(1);
  std::unique_ptr<WholeDomainView> view;
  const MeshPart* part = nullptr;
  PartOnly() {
    auto tissue = std::make_unique<DistributedMonodomain>("tissue", SlabInBlocks(1),
                                                          SlabParams("jacobi"), World());
    part = &tissue->part();
    view = std::make_unique<WholeDomainView>(std::move(tissue), *part, World());
  }
};

// Points are located on the parts as on the whole mesh: inside (random, and the whole mesh's
// nodes and face centroids, which lie on the parts' cuts), and outside (clamped to the nearest
// point of the mesh). A linear field is interpolated exactly by any tet holding a point, so its
// values tell whether the weights reproduce the serial map's; the maps are the same on every
// rank.
TEST(WholeDomainView, APartOnlyViewLocatesPointsAsTheWholeMesh) {
  PartOnly s;
  const Mesh& whole = *s.whole;
  ASSERT_FALSE(s.view->holds_whole_domain());
  EXPECT_EQ(s.view->domain().num_tets(), static_cast<Index>(s.part->whole_tet.size()));
  const double diag = (whole.nodes.rowwise().maxCoeff() - whole.nodes.rowwise().minCoeff()).norm();
  EXPECT_NEAR(s.view->WholeDiagonal(), diag, 1e-15 * diag);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Vec3 size(0.020, 0.007, 0.003);
  Points inside(3, 0), outside(3, 6);
  std::vector<Vec3> points;
  for (int i = 0; i < 200; ++i)
    points.emplace_back(size.cwiseProduct(Vec3(unit(random), unit(random), unit(random))));
  for (Index v = 0; v < whole.num_nodes(); v += 37) points.emplace_back(whole.nodes.col(v));
  for (Index e = 0; e < whole.num_tets(); e += 53)
    points.emplace_back((whole.nodes.col(whole.tets(0, e)) + whole.nodes.col(whole.tets(1, e)) +
                         whole.nodes.col(whole.tets(2, e))) /
                        3);
  inside.resize(3, static_cast<Index>(points.size()));
  for (std::size_t j = 0; j < points.size(); ++j) inside.col(static_cast<Index>(j)) = points[j];
  outside << -0.001, 0.021, 0.010, 0.005, 0.030, -0.002,  //
      0.003, 0.004, -0.001, 0.008, 0.003, 0.009,          //
      0.001, 0.001, 0.002, 0.0035, -0.001, 0.004;
  const Vec3 gradient(1.0, -2.0, 3.0);
  for (const Points* targets : {&inside, &outside}) {
    const PointMap serial = PointMap::BarycentricInTets(whole.nodes, whole.tets, *targets);
    const PointMap split = s.view->LocateWhole(*targets);
    EXPECT_NEAR(split.max_distance(), serial.max_distance(), 1e-12 * diag);
    for (Index j = 0; j < targets->cols(); ++j) {
      Vec3 at_split = Vec3::Zero(), at_serial = Vec3::Zero();
      for (int k = 0; k < 4; ++k) {
        at_split += split.weights()(k, j) * whole.nodes.col(split.indices()(k, j));
        at_serial += serial.weights()(k, j) * whole.nodes.col(serial.indices()(k, j));
      }
      EXPECT_LT((at_split - at_serial).norm(), 1e-12 * diag) << "point " << j;
      EXPECT_NEAR(gradient.dot(at_split), gradient.dot(at_serial), 1e-12 * diag);
    }
    // The same map on every rank.
    std::vector<double> mine(split.weights().data(),
                             split.weights().data() + split.weights().size());
    for (Index i = 0; i < split.indices().size(); ++i) mine.push_back(split.indices().data()[i]);
    std::vector<double> low = mine, high = mine;
    MPI_Allreduce(MPI_IN_PLACE, low.data(), static_cast<int>(low.size()), MPI_DOUBLE, MPI_MIN,
                  World());
    MPI_Allreduce(MPI_IN_PLACE, high.data(), static_cast<int>(high.size()), MPI_DOUBLE, MPI_MAX,
                  World());
    EXPECT_EQ(low, high);
  }
}

// Regions select the whole mesh's nodes, on every rank the same sorted list, from the parts.
TEST(WholeDomainView, APartOnlyViewSelectsTheWholeMeshsNodes) {
  PartOnly s;
  const std::vector<Region> regions = {
      AllRegion{},
      BoxRegion{Vec3(0.004, 0.001, 0.0), Vec3(0.011, 0.005, 0.0015)},
      SphereRegion{Vec3(0.010, 0.0035, 0.0015), 0.003},
      HalfSpaceRegion{Vec3(0.015, 0, 0), Vec3(1, 0.2, 0)},
      GroupRegion{"xmin"},
      GroupRegion{"xmax"},
      GroupRegion{"ymin"},
      GroupRegion{"ymax"},
      GroupRegion{"zmin"},
      GroupRegion{"zmax"},
      GroupRegion{"volume"},
      NodeIdsRegion{{40, 3, 3, 7}}};
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const std::vector<int> expected = SelectNodes(regions[r], *s.whole);
    EXPECT_EQ(s.view->SelectWholeNodes(regions[r]), expected) << "region " << r;
  }
  EXPECT_THROW((void)s.view->SelectWholeNodes(NodeIdsRegion{{-1}}), InputError);
  EXPECT_THROW((void)s.view->SelectWholeNodes(GroupRegion{"no such group"}), InputError);

  // Region probes reduce where the nodes are owned: the owners' selections, of a part-only view
  // and of a view with the whole mesh, put together are the whole mesh's, each node once.
  auto tissue =
      std::make_unique<DistributedMonodomain>("whole", *s.whole, SlabParams("jacobi"), World());
  const MeshPart& cut = tissue->part();
  const WholeDomainView whole_view(std::move(tissue), cut, s.whole, World());
  for (const WholeDomainView* view :
       {static_cast<const WholeDomainView*>(s.view.get()), &whole_view}) {
    const MeshPart& part = view == s.view.get() ? *s.part : cut;
    for (std::size_t r = 0; r < regions.size(); ++r) {
      std::vector<int> mine;
      for (const int i : view->SelectOwnedNodes(regions[r])) {
        ASSERT_LT(i, part.num_owned) << "region " << r;
        mine.push_back(part.whole_node[static_cast<std::size_t>(i)]);
      }
      int count = static_cast<int>(mine.size());
      std::vector<int> counts(static_cast<std::size_t>(Size())),
          offsets(static_cast<std::size_t>(Size()), 0);
      MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, World());
      std::partial_sum(counts.begin(), counts.end() - 1, offsets.begin() + 1);
      std::vector<int> all(static_cast<std::size_t>(offsets.back() + counts.back()));
      MPI_Allgatherv(mine.data(), count, MPI_INT, all.data(), counts.data(), offsets.data(),
                     MPI_INT, World());
      std::sort(all.begin(), all.end());  // repeated nodes stay: each must come once
      EXPECT_EQ(all, SelectNodes(regions[r], *s.whole)) << "region " << r;
    }
    EXPECT_THROW((void)view->SelectOwnedNodes(NodeIdsRegion{{-1}}), InputError);
  }
  std::array<double, 3> values{static_cast<double>(Rank()), 1.0, -static_cast<double>(Rank())};
  whole_view.CombineAcross(values, PartitionedObject::Combine::kSum);
  EXPECT_EQ(values[1], Size());
  whole_view.CombineAcross(values, PartitionedObject::Combine::kMax);
  EXPECT_EQ(values[0], Size() * (Size() - 1) / 2);
}

// Reading whole-mesh nodes gives each node's value from its owner, on every rank: equal, bit for
// bit, to the value any rank holding the node has (shared nodes are stepped alike).
TEST(WholeDomainView, APartOnlyViewReadsEachNodeFromItsOwner) {
  PartOnly s;
  for (int step = 0; step < 300; ++step) ASSERT_TRUE(s.view->Step(1e-5).ok());  // an upstroke
  const FieldId v = s.view->FindField("V");
  std::vector<int> all(static_cast<std::size_t>(s.whole->num_nodes()));
  std::iota(all.begin(), all.end(), 0);
  std::reverse(all.begin(), all.end());
  all.push_back(5);  // a repeated node
  Eigen::MatrixXd values(1, static_cast<Index>(all.size()));
  s.view->ReadWholeNodes(v, all, values);
  Eigen::MatrixXd local(1, s.view->FieldCount(v));
  s.view->ReadField(v, local);  // the part's own nodes
  const auto n = static_cast<int>(s.whole->num_nodes());
  for (std::size_t i = 0; i < s.part->whole_node.size(); ++i) {
    const int node = s.part->whole_node[i];
    EXPECT_EQ(std::bit_cast<std::uint64_t>(values(0, n - 1 - node)),
              std::bit_cast<std::uint64_t>(local(0, static_cast<Index>(i))))
        << "node " << node;
  }
  EXPECT_EQ(values(0, n), values(0, n - 1 - 5));
  double low = values.minCoeff(), high = values.maxCoeff();
  EXPECT_LT(low, -80);  // resting tissue, and
  EXPECT_GT(high, 0);   // the stimulated corner's upstroke
}

// The headline check: the benchmark slab at 0.5 mm on 2 or 4 ranks activates every node at the
// serial object's time, and the global fields (activated fraction, voltage integral) are the
// serial ones.
TEST(DistributedMonodomain, BenchmarkSlabActivatesEveryNodeAtTheSerialTime) {
  const auto whole = Slab(2);
  const double dt = 1e-5;    // s
  const double end = 0.130;  // s: past the far corner's activation (about 127 ms)
  DistributedMonodomain tissue("tissue", *whole, SlabParams("jacobi"), World());
  const auto steps = static_cast<long>(std::llround(end / dt));
  StepStatus status;
  for (long s = 0; s < steps && status.ok(); ++s) status = tissue.Step(dt);
  ASSERT_TRUE(status.ok()) << status.what;
  const std::vector<double> distributed = tissue.Gather(tissue.activation_time().data());
  // The global fields are reductions over the ranks.
  Eigen::MatrixXd fraction(1, 1), integral(1, 1);
  tissue.ReadField(tissue.FindField("activated_fraction"), fraction);
  tissue.ReadField(tissue.FindField("voltage_integral"), integral);
  int ok = 1;
  if (Rank() == 0) {
    Monodomain serial("serial", whole, SlabParams("jacobi"));
    StepStatus s_status;
    for (long s = 0; s < steps && s_status.ok(); ++s) s_status = serial.Step(dt);
    EXPECT_TRUE(s_status.ok()) << s_status.what;
    const VecX& reference = serial.activation_time();
    double worst = 0;
    Index worst_node = -1;
    for (Index i = 0; i < whole->num_nodes(); ++i) {
      EXPECT_GT(reference[i], 0) << "node " << i << " never activated in the serial run";
      const double diff = std::abs(distributed[static_cast<std::size_t>(i)] - reference[i]);
      if (diff > worst) {
        worst = diff;
        worst_node = i;
      }
    }
    RecordProperty("max_activation_difference_ms", std::to_string(worst));
    std::printf("slab 0.5 mm on %d ranks: max |activation time - serial| = %.3g ms (node %ld)\n",
                Size(), worst, static_cast<long>(worst_node));
    EXPECT_LT(worst, kActivationBound) << "at node " << worst_node;
    Eigen::MatrixXd s_fraction(1, 1), s_integral(1, 1);
    serial.ReadField(serial.FindField("activated_fraction"), s_fraction);
    serial.ReadField(serial.FindField("voltage_integral"), s_integral);
    EXPECT_EQ(fraction(0, 0), 1.0);
    EXPECT_EQ(s_fraction(0, 0), 1.0);
    EXPECT_NEAR(integral(0, 0), s_integral(0, 0), 1e-6 * std::abs(s_integral(0, 0)));
    ok = ::testing::Test::HasFailure() ? 0 : 1;
  }
  MPI_Bcast(&ok, 1, MPI_INT, 0, World());
  EXPECT_EQ(ok, 1);
}

// A slab made block by block (no rank holds it whole) runs bitwise as the whole slab cut on
// every rank: the same parts, and the same stimulus nodes from a box, a triangle group and
// whole-mesh node ids, selected by each rank among its own nodes.
TEST(DistributedMonodomain, ASlabMadeInBlocksRunsAsTheWholeSlab) {
  const auto whole = Slab(2);
  EpTissueParams params = SlabParams("jacobi");
  StimulusSpec face = params.stimuli.front();
  face.name = "xmax face";
  face.region = GroupRegion{"xmax"};
  face.pulses.start = 5.0;
  params.stimuli.push_back(face);
  StimulusSpec node = face;
  node.name = "one node";
  node.region = NodeIdsRegion{{static_cast<int>(whole->num_nodes()) / 2}};
  params.stimuli.push_back(node);
  const double dt = 1e-5;
  const long steps = 1500;  // 15 ms: the three stimuli have fired
  DistributedMonodomain a("a", *whole, params, World());
  DistributedMonodomain b("b", SlabInBlocks(2), params, World());
  for (long s = 0; s < steps; ++s) {
    ASSERT_TRUE(a.Step(dt).ok());
    ASSERT_TRUE(b.Step(dt).ok());
  }
  ASSERT_EQ(a.part().whole_node, b.part().whole_node);
  const VecX &ta = a.activation_time(), &tb = b.activation_time();
  ASSERT_EQ(ta.size(), tb.size());
  int activated = 0;
  for (Index i = 0; i < ta.size(); ++i) {
    ASSERT_EQ(std::bit_cast<std::uint64_t>(ta[i]), std::bit_cast<std::uint64_t>(tb[i]))
        << "node " << i;
    activated += ta[i] >= 0 ? 1 : 0;
  }
  // Every stimulus took: the front has left the corner, the xmax face and the middle node.
  int activated_all = activated;
  MPI_Allreduce(MPI_IN_PLACE, &activated_all, 1, MPI_INT, MPI_SUM, World());
  EXPECT_GT(activated_all, static_cast<int>(whole->num_nodes()) / 10);
}

// A stimulus on a face group of a mesh made in blocks drives every copy of the face's nodes:
// a rank that holds a node of the face but none of its triangles takes it too (shared nodes
// are stepped alike on every rank only if they are driven alike).
TEST(DistributedMonodomain, AFaceGroupStimulusDrivesEveryCopyOfItsNodes) {
  // Coarse boxes of five tets per cell: their parts' cuts meet the faces at irregular lines.
  const Vec3 size(0.020, 0.007, 0.003);
  int without_triangle = 0;
  for (const std::array<int, 3> cells : {std::array<int, 3>{6, 3, 2}, {5, 4, 3}, {7, 2, 3}})
    for (const char* face : {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"}) {
      const Mesh whole = MakeTetBox(Vec3::Zero(), size, cells, HexSplit::kFive);
      EpTissueParams params = SlabParams("jacobi");
      params.stimuli.front().region = GroupRegion{face};
      DistributedMonodomain tissue(
          "tissue",
          PartitionMeshBlocks(
              MakeTetBoxBlock(Vec3::Zero(), size, cells, HexSplit::kFive, Rank(), Size()), World()),
          params, World());
      const MeshPart& part = tissue.part();
      const std::vector<int> expected = SelectNodes(GroupRegion{face}, whole);
      without_triangle += static_cast<int>(SelectNodes(GroupRegion{face}, *part.mesh).size());
      std::vector<int> driven;
      for (const int i : tissue.stimulus_nodes().front())
        driven.push_back(part.whole_node[static_cast<std::size_t>(i)]);
      std::sort(driven.begin(), driven.end());
      std::vector<int> held;  // this part's nodes of the face
      for (const int w : part.whole_node)
        if (std::binary_search(expected.begin(), expected.end(), w)) held.push_back(w);
      std::sort(held.begin(), held.end());
      EXPECT_EQ(driven, held) << face;
      without_triangle -= static_cast<int>(held.size());
    }
  // The case the gathering is for: on 4 ranks some rank holds face nodes that its own
  // triangles do not name (the 2-way cuts of these boxes are clean: no such node).
  MPI_Allreduce(MPI_IN_PLACE, &without_triangle, 1, MPI_INT, MPI_MIN, World());
  if (Size() >= 4) {
    EXPECT_LT(without_triangle, 0);
  }
}

// A region that selects no node of a mesh made in blocks is refused on every rank, as on the
// whole mesh.
TEST(DistributedMonodomain, ARegionOutsideAMeshMadeInBlocksIsRefusedOnEveryRank) {
  EpTissueParams params = SlabParams("jacobi");
  params.stimuli.front().region = BoxRegion{Vec3::Constant(1.0), Vec3::Constant(2.0)};
  auto build = [&] { DistributedMonodomain tissue("tissue", SlabInBlocks(1), params, World()); };
  EXPECT_THROW(build(), InputError);
}

// CG with PETSc's algebraic multigrid preconditioners (GAMG, hypre's BoomerAMG) or with Jacobi
// reaches the activation times of a direct solve (MUMPS's Cholesky across ranks): the solver
// changes the iterates, not the solution (same tolerance and bound as above, on a shorter run).
TEST(DistributedMonodomain, IterativeSolversReachTheDirectSolvesActivationTimes) {
  const auto whole = Slab(2);
  const double dt = 1e-5;
  const long steps = 2500;  // 25 ms: the front a third of the way along the slab
  std::vector<std::vector<double>> times;
  std::vector<double> iterations;
  for (const char* pc : {"jacobi", "amg", "hypre", "direct"}) {
    const std::string name = pc;
    DistributedMonodomain tissue(
        "tissue", *whole, name == "direct" ? SlabParams("jacobi", "cholmod") : SlabParams(pc),
        World());
    StepStatus status;
    for (long s = 0; s < steps && status.ok(); ++s) status = tissue.Step(dt);
    ASSERT_TRUE(status.ok()) << pc << ": " << status.what;
    times.push_back(tissue.Gather(tissue.activation_time().data()));
    if (Rank() == 0) std::printf("%s: %s\n", pc, tissue.solver_name().c_str());
  }
  if (Rank() != 0) return;
  const std::vector<double>& direct = times.back();
  int activated = 0;
  for (std::size_t k = 0; k + 1 < times.size(); ++k) {
    double worst = 0;
    for (std::size_t i = 0; i < direct.size(); ++i) {
      ASSERT_EQ(times[k][i] >= 0, direct[i] >= 0) << "solver " << k << ", node " << i;
      worst = std::max(worst, std::abs(times[k][i] - direct[i]));
    }
    std::printf("solver %zu: max |activation time - direct| = %.3g ms\n", k, worst);
    EXPECT_LT(worst, kActivationBound) << "solver " << k;
  }
  for (double t : direct) activated += t >= 0 ? 1 : 0;
  EXPECT_GT(activated, static_cast<int>(direct.size()) / 10);  // the front has moved
}

// A rank whose cells blow up stops every rank in the same step: the diverging rank names the
// node (in the whole mesh's numbering), the others say which rank it was.
TEST(DistributedMonodomain, ARankThatDivergesStopsEveryRankInTheSameStep) {
  const auto whole = Slab(1);
  DistributedMonodomain tissue("tissue", *whole, SlabParams("jacobi"), World());
  const double dt = 1e-5;
  for (int s = 0; s < 3; ++s) ASSERT_TRUE(tissue.Step(dt).ok());
  const int bad_rank = Size() - 1;
  if (Rank() == bad_rank) {
    // An owned node's voltage beyond any cardiac potential (finite: the solve goes through).
    Eigen::MatrixXd v(1, tissue.num_nodes());
    tissue.ReadField(tissue.FindField("V"), v);
    v(0, 0) = 5e4;
    tissue.WriteField(tissue.FindField("V"), v);
  }
  const StepStatus status = tissue.Step(dt);
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(status.code, StepStatus::Code::kDiverged);
  if (Rank() == bad_rank) {
    EXPECT_EQ(status.item, tissue.part().whole_node[0]);
  } else {
    EXPECT_EQ(status.item, bad_rank);
    EXPECT_STREQ(status.what, "another rank's part of the object diverged");
  }
}

}  // namespace
}  // namespace gipsi
