// Connectors between split objects (parallel/whole_domain_view.h): objects split alike are
// coupled part to part, with no whole-field gather, and give every item the value the
// whole-field path gives it. Runs under `mpiexec -np 2` and `-np 4 --oversubscribe`
// (tests/CMakeLists.txt); every test is collective.

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "gipsi/base/error.h"
#include "gipsi/core/coordinator.h"
#include "gipsi/core/partitioned_object.h"
#include "gipsi/core/port.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/mapping.h"
#include "gipsi/geometry/mesh_block.h"
#include "gipsi/models/connectors/excitation_contraction.h"
#include "gipsi/models/connectors/field_copy.h"
#include "gipsi/models/connectors/item_positions.h"
#include "gipsi/models/ep/phenomenological.h"
#include "gipsi/models/fem/fem_solid.h"
#include "gipsi/models/fem/solid_laws.h"
#include "gipsi/parallel/distributed_monodomain.h"
#include "gipsi/parallel/distributed_solid.h"
#include "gipsi/parallel/mesh_partition.h"
#include "gipsi/parallel/parallel_session.h"
#include "gipsi/parallel/whole_domain_view.h"

namespace gipsi {
namespace {

MPI_Comm World() { return ParallelSession::world(); }

// A 10 × 4 × 2 mm box of Aliev–Panfilov tissue, stimulated in the corner at x = 0 for 2 ms: after
// 6 ms V runs from rest (u = 0) through the wave front to the plateau (u near 1).
std::shared_ptr<const Mesh> Box(double length = 0.010) {
  return std::make_shared<Mesh>(MakeTetBox(Vec3::Zero(), Vec3(length, 0.004, 0.002), {20, 8, 4}));
}

EpTissueParams TissueParams() {
  EpTissueParams p;
  p.cell = std::make_shared<AlievPanfilov>();
  p.sigma_longitudinal = p.sigma_transverse = 0.1;
  p.fibre = Vec3::UnitX();
  p.linear.preconditioner = "jacobi";
  p.linear.tolerance = 1e-10;
  StimulusSpec corner;
  corner.name = "corner";
  corner.region = BoxRegion{Vec3::Constant(-1e-6), Vec3(0.002, 0.004, 0.002)};
  corner.amplitude = 50;
  corner.pulses.duration = 2.0;
  p.stimuli.push_back(corner);
  return p;
}

std::unique_ptr<WholeDomainView> SplitTissue(std::shared_ptr<const Mesh> whole) {
  auto part = std::make_unique<DistributedMonodomain>("ep", *whole, TissueParams(), World());
  const MeshPart& mesh_part = part->part();
  return std::make_unique<WholeDomainView>(std::move(part), mesh_part, whole, World());
}

FemParams MuscleParams() {
  FemParams p;
  p.material = std::make_shared<CorotationalSolid>(1e5, 0.45);
  p.fibre = Vec3::UnitX();
  p.gravity = Vec3::Zero();
  return p;
}

// The serial muscle, or the view on this rank's part of it.
std::unique_ptr<SimObject> Muscle(std::shared_ptr<const Mesh> whole, bool split) {
  FemParams p = MuscleParams();
  if (!split) return std::make_unique<FemSolid>("muscle", whole, std::move(p));
  auto distribution = std::make_shared<DistributedSolid>(whole, World());
  p.distribution = distribution;
  const MeshPart& part = distribution->part();
  return std::make_unique<WholeDomainView>(
      std::make_unique<FemSolid>("muscle", part.mesh, std::move(p)), part, whole, World(),
      WholeDomainView::BoundaryMap{distribution->whole_boundary_vertex(),
                                   distribution->whole_boundary_face()});
}

// This rank's part of Box() (or of another box), made from blocks (no rank holds the whole box).
MeshPart BoxInBlocks(const Vec3& lo = Vec3::Zero(), const Vec3& hi = Vec3(0.010, 0.004, 0.002),
                     const std::array<int, 3>& cells = {20, 8, 4}) {
  return PartitionMeshBlocks(
      MakeTetBoxBlock(lo, hi, cells, HexSplit::kSix, ParallelSession::rank(World()),
                      ParallelSession::size(World())),
      World());
}

// A coarser box on another grid, reaching 1.5 mm past the tissue's end in x and 0.5 mm below it
// in y: its items there lie outside the tissue.
const Vec3 kOtherLo(0.001, -0.0005, 0), kOtherHi(0.0115, 0.0045, 0.002);
constexpr std::array<int, 3> kOtherCells = {7, 3, 2};

// The tissue and the muscle made in blocks, behind views without the whole box (as a scene run
// makes the heart's).
std::unique_ptr<WholeDomainView> TissueInBlocks() {
  auto part = std::make_unique<DistributedMonodomain>("ep", BoxInBlocks(), TissueParams(), World());
  const MeshPart& mesh_part = part->part();
  return std::make_unique<WholeDomainView>(std::move(part), mesh_part, World());
}

std::unique_ptr<WholeDomainView> MuscleInBlocks(MeshPart cut = BoxInBlocks()) {
  FemParams p = MuscleParams();
  auto distribution = std::make_shared<DistributedSolid>(std::move(cut), World());
  p.distribution = distribution;
  const MeshPart& part = distribution->part();
  return std::make_unique<WholeDomainView>(
      std::make_unique<FemSolid>("muscle", part.mesh, std::move(p)), part, World(),
      WholeDomainView::BoundaryMap{
          distribution->whole_boundary_vertex(), distribution->whole_boundary_face(),
          distribution->whole_boundary_vertices(), distribution->whole_boundary_faces()});
}

Eigen::MatrixXd Read(const SimObject& object, const std::string& field) {
  const FieldId id = object.FindField(field);
  Eigen::MatrixXd out(object.field_info(id).components, object.FieldCount(id));
  object.ReadField(id, out);
  return out;
}

const ExcitationContractionParams kTwitch{
    .v_rest = -80, .v_peak = 20, .threshold = 0.05, .gain = 4e4, .rise_rate = 8, .decay_rate = 25};

// The twitch law at a voltage, from a tension `from` over `dt` (the connector's documented
// exact step).
double Twitch(double v, double from, double dt) {
  const ExcitationContractionParams& p = kTwitch;
  const double u = std::clamp((v - p.v_rest) / (p.v_peak - p.v_rest), 0.0, 1.0);
  const double rate = u >= p.threshold ? p.rise_rate : p.decay_rate;
  return p.gain * u + (from - p.gain * u) * std::exp(-rate * dt);
}

// Every tet of the muscle's part holds the twitch law's tension after 4 ms from rest at V of its
// centroid: the mean of its corners' whole-mesh `volts` (barycentric weights of 1/4).
void ExpectTwitchAtCentroids(const PartitionedObject& muscle, const Mesh& whole,
                             const Eigen::MatrixXd& volts) {
  const Eigen::MatrixXd local = Read(muscle.local_part(), "active_tension");
  const std::span<const int> tets = muscle.whole_tets_of_part();
  for (Index i = 0; i < local.cols(); ++i) {
    const int e = tets[static_cast<std::size_t>(i)];
    double mean = 0;
    for (int a = 0; a < 4; ++a) mean += 0.25 * volts(0, whole.tets(a, e));
    ASSERT_NEAR(local(0, i), Twitch(mean, 0.0, 0.004), 1e-9) << "tet " << e;
  }
}

// Every rank's shared nodes take their owners' values, for one and for three components; the
// owned ones are left as they were.
TEST(SplitCoupling, SharedNodesTakeTheirOwnersValues) {
  const auto tissue = SplitTissue(Box());
  const std::span<const int> whole = tissue->whole_nodes_of_part();
  const Index owned = tissue->num_owned_nodes();
  for (int components : {1, 3}) {
    Eigen::MatrixXd values(components, static_cast<Index>(whole.size()));
    for (Index i = 0; i < values.cols(); ++i)
      for (int k = 0; k < components; ++k)
        values(k, i) = i < owned ? 10.0 * whole[static_cast<std::size_t>(i)] + k : -1.0;
    tissue->ShareOwnedNodeValues(values);
    for (Index i = 0; i < values.cols(); ++i)
      for (int k = 0; k < components; ++k)
        ASSERT_EQ(values(k, i), 10.0 * whole[static_cast<std::size_t>(i)] + k)
            << "local node " << i << " (owned: " << owned << "), component " << k;
  }
}

// A non-finite value one rank meets in its part is reported alike on every rank: the smallest
// whole-mesh index of the ranks' first such nodes (or tets).
TEST(SplitCoupling, ANonFiniteValueIsAgreedOnEveryRank) {
  const auto tissue = SplitTissue(Box());
  const int rank = ParallelSession::rank(World()), size = ParallelSession::size(World());
  const std::span<const int> nodes = tissue->whole_nodes_of_part();
  const std::span<const int> tets = tissue->whole_tets_of_part();
  Eigen::MatrixXd at_nodes = Eigen::MatrixXd::Zero(2, static_cast<Index>(nodes.size()));
  Eigen::MatrixXd at_tets = Eigen::MatrixXd::Zero(1, static_cast<Index>(tets.size()));
  EXPECT_FALSE(FirstNonFinite(at_nodes, FieldLocation::kNode, tissue.get()));
  // The last rank's last node, rank 0's middle node and first tet: the node reported is the
  // smaller of the two nodes' whole indices, the tet rank 0's.
  constexpr int kNone = std::numeric_limits<int>::max();
  int planted[3] = {kNone, kNone, kNone};  // rank 0's node, the last rank's node, rank 0's tet
  if (rank == size - 1) {
    at_nodes(1, at_nodes.cols() - 1) = std::numeric_limits<double>::infinity();
    planted[1] = nodes.back();
  }
  if (rank == 0) {
    at_nodes(0, at_nodes.cols() / 2) = std::numeric_limits<double>::quiet_NaN();
    planted[0] = nodes[nodes.size() / 2];
    at_tets(0, 0) = std::numeric_limits<double>::quiet_NaN();
    planted[2] = tets[0];
  }
  MPI_Allreduce(MPI_IN_PLACE, planted, 3, MPI_INT, MPI_MIN, World());
  const auto node = FirstNonFinite(at_nodes, FieldLocation::kNode, tissue.get());
  ASSERT_TRUE(node);
  EXPECT_EQ(node->item, std::min(planted[0], planted[1]));
  EXPECT_TRUE(std::isnan(node->value));
  const auto tet = FirstNonFinite(at_tets, FieldLocation::kElement, tissue.get());
  ASSERT_TRUE(tet);
  EXPECT_EQ(tet->item, planted[2]);
}

// The tissue and a muscle on the same mesh are split alike on every rank; on another mesh, or
// with the muscle whole on every rank, they are not (and every rank says so alike).
TEST(SplitCoupling, ObjectsOnOneMeshAreSplitAlike) {
  const auto mesh = Box();
  const auto tissue = SplitTissue(mesh);
  EXPECT_TRUE(SplitAlike(*tissue, *Muscle(mesh, true)));
  EXPECT_FALSE(SplitAlike(*tissue, *Muscle(mesh, false)));
  EXPECT_FALSE(SplitAlike(*tissue, *Muscle(Box(0.011), true)));
}

// The excitation–contraction coupling of a split tissue and a split muscle on one mesh couples
// the parts: no whole field is gathered, and every local item of every part (owned or shared)
// gets the twitch law's value at the whole mesh's V, on nodes and, through the interpolation on
// the part, at the tets' centroids. With the muscle whole on every rank the connector reads V
// whole for its nodes, and asks the tissue's parts for V at its tets' centroids, and gives the
// same values.
TEST(SplitCoupling, ExcitationContractionCouplesThePartsWithoutGathers) {
  const auto mesh = Box();
  const auto tissue = SplitTissue(mesh);
  for (int s = 0; s < 60; ++s) ASSERT_TRUE(tissue->Step(1e-4).ok());  // 6 ms
  const Eigen::MatrixXd volts = Read(*tissue, "V");
  ASSERT_LT(volts.minCoeff(), -70.0);  // rest and plateau both present
  ASSERT_GT(volts.maxCoeff(), 0.0);
  const FieldId v = tissue->FindField("V");
  // Each field on muscles of its own (a FemSolid's element tension reads its nodal one's mean
  // once that is written).
  for (const char* field : {"nodal_active_tension", "active_tension"}) {
    SCOPED_TRACE(field);
    std::unique_ptr<SimObject> split_muscle = Muscle(mesh, true),
                               whole_muscle = Muscle(mesh, false);
    ExcitationContraction on_parts("ec", *tissue, v, *split_muscle, split_muscle->FindField(field),
                                   kTwitch);
    ExcitationContraction whole_v("ec", *tissue, v, *whole_muscle, whole_muscle->FindField(field),
                                  kTwitch);
    EXPECT_TRUE(on_parts.couples_parts());
    // Onto the whole muscle's nodes item for item, reading V whole; onto its tets through the
    // parts that hold their centroids.
    const bool at_tets = std::string(field) == "active_tension";
    EXPECT_EQ(whole_v.couples_parts(), at_tets);
    const std::int64_t reads_before = tissue->whole_field_reads();
    for (double t : {0.0, 0.004}) ASSERT_TRUE(on_parts.Fire(t).ok());
    EXPECT_EQ(tissue->whole_field_reads(), reads_before);
    EXPECT_EQ(dynamic_cast<const WholeDomainView&>(*split_muscle).whole_field_reads(), 0);
    for (double t : {0.0, 0.004}) ASSERT_TRUE(whole_v.Fire(t).ok());
    EXPECT_EQ(tissue->whole_field_reads(), reads_before + (at_tets ? 0 : 2));

    const auto& part = dynamic_cast<PartitionedObject&>(*split_muscle);
    const Eigen::MatrixXd local = Read(part.local_part(), field);
    if (std::string(field) == "nodal_active_tension") {
      // Every local node of the muscle's part, shared ones too, as at the whole mesh's node.
      const std::span<const int> nodes = part.whole_nodes_of_part();
      for (Index i = 0; i < local.cols(); ++i) {
        const int n = nodes[static_cast<std::size_t>(i)];
        ASSERT_EQ(local(0, i), Twitch(volts(0, n), 0.0, 0.004)) << "local node " << i;
      }
    } else {
      ExpectTwitchAtCentroids(part, *mesh, volts);
    }
    EXPECT_EQ(Read(*whole_muscle, field), Read(*split_muscle, field));
  }
}

// A FieldCopy of V (scaled to a tension: 2 kPa/mV) between the same split objects copies the
// parts, item for item onto the nodes and barycentrically onto the tets, with no gather; the
// values are those of the copy onto a whole muscle at every item. (Nearest-item copies:
// ANearestCopyJoinsObjectsSplitAnyWay.)
TEST(SplitCoupling, FieldCopyCopiesThePartsWithoutGathers) {
  const auto mesh = Box();
  const auto tissue = SplitTissue(mesh);
  for (int s = 0; s < 60; ++s) ASSERT_TRUE(tissue->Step(1e-4).ok());  // 6 ms
  const FieldId v = tissue->FindField("V");
  using Mapping = FieldCopy::Mapping;
  for (const char* field : {"nodal_active_tension", "active_tension"}) {
    SCOPED_TRACE(field);
    std::unique_ptr<SimObject> split_muscle = Muscle(mesh, true),
                               whole_muscle = Muscle(mesh, false);
    FieldCopy on_parts("copy", *tissue, v, *split_muscle, split_muscle->FindField(field),
                       Mapping::kAuto, 2, "kPa/mV");
    FieldCopy whole_v("copy", *tissue, v, *whole_muscle, whole_muscle->FindField(field),
                      Mapping::kAuto, 2, "kPa/mV");
    EXPECT_TRUE(on_parts.couples_parts());
    // Onto the whole muscle's nodes item for item, reading V whole; onto its tets through the
    // parts that hold their centroids.
    EXPECT_EQ(whole_v.couples_parts(), std::string(field) == "active_tension");
    EXPECT_EQ(on_parts.mapping(),
              std::string(field) == "active_tension" ? Mapping::kBarycentric : Mapping::kDirect);
    const std::int64_t reads_before = tissue->whole_field_reads();
    ASSERT_TRUE(on_parts.Fire(0).ok());
    EXPECT_EQ(tissue->whole_field_reads(), reads_before);
    ASSERT_TRUE(whole_v.Fire(0).ok());
    const Eigen::MatrixXd copied = Read(*split_muscle, field);
    EXPECT_LE((Read(*whole_muscle, field) - copied).cwiseAbs().maxCoeff(),
              1e-12 * copied.cwiseAbs().maxCoeff());
    EXPECT_GT(copied.cwiseAbs().maxCoeff(), 1e5);  // Pa: 2 kPa/mV of tens of mV
  }
}

// A connector that reads a node field whole, as a connector that does not couple parts does.
class WholeReader final : public Connector {
 public:
  explicit WholeReader(const SimObject& from) : Connector("reader") {
    BindNoState();
    UseField("from", from, "V", FieldAccess::kRead);
  }
  [[nodiscard]] std::string_view type_name() const override { return "WholeReader"; }

 protected:
  StepStatus DoFire(double /*t*/) override { return StepStatus::Ok(); }
};

// Objects made in blocks from one mesh (no rank holds it) are split alike, and the
// excitation–contraction coupling couples their parts: every muscle tet gets the twitch law at
// the mean of its corners' V, which the tissue split from the whole box gives too. A coordinator
// takes the pair, and the coupling to a muscle whole on every rank (the tissue's parts answer
// for its tets). A connector that cannot couple parts is refused on such an object when the
// coordinator prepares, naming the connector, the field and why. (A
// connector of its global fields and capabilities, the heart's cavity coupling, is taken:
// Mpi.SceneRunMatchesTheSerialRun runs the heart in blocks.)
TEST(SplitCoupling, ObjectsMadeInBlocksCoupleTheirPartsAndOtherConnectorsAreRefused) {
  const auto mesh = Box();
  std::unique_ptr<SimObject> tissue = TissueInBlocks();
  std::unique_ptr<SimObject> muscle = MuscleInBlocks();
  const auto whole_tissue = SplitTissue(mesh);
  ASSERT_FALSE(dynamic_cast<PartitionedObject&>(*tissue).holds_whole_domain());
  ASSERT_FALSE(dynamic_cast<PartitionedObject&>(*muscle).holds_whole_domain());
  EXPECT_TRUE(SplitAlike(*tissue, *muscle));
  EXPECT_TRUE(SplitAlike(*tissue, *whole_tissue));  // Scotch cuts the blocks as the whole box
  for (int s = 0; s < 60; ++s) {
    ASSERT_TRUE(tissue->Step(1e-4).ok());  // 6 ms
    ASSERT_TRUE(whole_tissue->Step(1e-4).ok());
  }
  const Eigen::MatrixXd volts = Read(*whole_tissue, "V");
  Coordinator coupled;
  SimObject* ep = tissue.get();
  SimObject* wall = muscle.get();
  coupled.AddObject(std::move(tissue), 1e-4);
  coupled.AddObject(std::move(muscle), 1e-4);
  coupled.AddConnector(
      std::make_unique<ExcitationContraction>("ec", *ep, ep->FindField("V"), *wall,
                                              wall->FindField("active_tension"), kTwitch),
      1);
  EXPECT_TRUE(coupled.connector(0).couples_parts());
  EXPECT_NO_THROW(coupled.Prepare(1e-4));
  ASSERT_TRUE(coupled.connector(0).Fire(0.0).ok());
  ASSERT_TRUE(coupled.connector(0).Fire(0.004).ok());
  ExpectTwitchAtCentroids(dynamic_cast<PartitionedObject&>(*wall), *mesh, volts);

  {  // EC to a muscle whole on every rank: the tissue's parts answer for its tets' centroids
    auto source = TissueInBlocks();
    for (int s = 0; s < 60; ++s) ASSERT_TRUE(source->Step(1e-4).ok());
    auto whole_muscle = Muscle(mesh, false);
    SimObject& whole_wall = *whole_muscle;
    auto ec = std::make_unique<ExcitationContraction>(
        "ec", *source, source->FindField("V"), *whole_muscle,
        whole_muscle->FindField("active_tension"), kTwitch);
    EXPECT_TRUE(ec->couples_parts());
    Coordinator c;
    c.AddObject(std::move(source), 1e-4);
    c.AddObject(std::move(whole_muscle), 1e-4);
    c.AddConnector(std::move(ec), 1);
    EXPECT_NO_THROW(c.Prepare(1e-4));
    ASSERT_TRUE(c.connector(0).Fire(0.0).ok());
    ASSERT_TRUE(c.connector(0).Fire(0.004).ok());
    const Eigen::MatrixXd tension = Read(whole_wall, "active_tension");
    for (Index e = 0; e < mesh->num_tets(); ++e) {
      double mean = 0;
      for (int a = 0; a < 4; ++a) mean += 0.25 * volts(0, mesh->tets(a, e));
      ASSERT_NEAR(tension(0, e), Twitch(mean, 0.0, 0.004), 1e-9) << "tet " << e;
    }
  }
  {  // a connector that reads V whole
    auto source = TissueInBlocks();
    auto reader = std::make_unique<WholeReader>(*source);
    EXPECT_FALSE(reader->couples_parts());
    Coordinator c;
    c.AddObject(std::move(source), 1e-4);
    c.AddConnector(std::move(reader), 1);
    try {
      c.Prepare(1e-4);
      ADD_FAILURE() << "accepted";
    } catch (const WiringError& e) {
      EXPECT_NE(std::string(e.what()).find("connector 'reader' (WholeReader) reads field 'V' of "
                                           "'ep' (Monodomain) at its 'from' key, but that object "
                                           "is made in blocks"),
                std::string::npos)
          << e.what();
    }
  }
}

// The parts answer for the points each rank asks at: every rank a different set (one none),
// inside the box, on its nodes (shared faces of parts), and outside it (one far off, nearest a
// corner): each value is the whole box's interpolation, within rounding (a point on a face
// between parts may take the other tet), and the farthest distance is the whole box's.
TEST(SplitCoupling, PartsInterpolateAtThePointsEachRankAsks) {
  const auto mesh = Box();
  const auto whole_tissue = SplitTissue(mesh);
  const auto tissue = TissueInBlocks();
  for (int s = 0; s < 60; ++s) {
    ASSERT_TRUE(tissue->Step(1e-4).ok());  // 6 ms
    ASSERT_TRUE(whole_tissue->Step(1e-4).ok());
  }
  const Eigen::MatrixXd volts = Read(*whole_tissue, "V");
  const int rank = ParallelSession::rank(World()), size = ParallelSession::size(World());
  // Rank r's points: 40 r + 7 nodes of the box from node 13 r on, three inside points, and for
  // rank 0 two outside; rank 1 asks for none.
  auto points_of = [&](int r) {
    if (r == 1) return Points(3, 0);
    std::vector<Vec3> at;
    for (int k = 0; k < 40 * r + 7; ++k)
      at.push_back(mesh->nodes.col((13 * r + 17 * k) % mesh->num_nodes()));
    for (int k = 0; k < 3; ++k) at.push_back(Vec3(0.0011 + 0.0029 * k + 1e-4 * r, 0.0013, 0.0007));
    if (r == 0) {
      at.push_back(Vec3(0.0105, 0.002, 0.001));  // 0.5 mm past the end
      at.push_back(Vec3(0.03, -0.01, 0.02));     // far off, nearest the corner (10, 0, 2) mm
    }
    Points out(3, static_cast<Index>(at.size()));
    for (std::size_t j = 0; j < at.size(); ++j) out.col(static_cast<Index>(j)) = at[j];
    return out;
  };
  const Points mine = points_of(rank);
  const auto interpolation = tissue->InterpolateAtPoints(mine);
  ASSERT_EQ(interpolation->num_points(), mine.cols());
  Eigen::MatrixXd values(1, mine.cols());
  const std::int64_t reads_before = tissue->whole_field_reads();
  interpolation->Interpolate(tissue->FindField("V"), values, std::nullopt);
  EXPECT_EQ(tissue->whole_field_reads(), reads_before);
  const PointMap serial = PointMap::BarycentricInTets(mesh->nodes, mesh->tets, mine);
  Eigen::MatrixXd expected(1, mine.cols());
  serial.Apply(volts, expected);
  const double peak = volts.cwiseAbs().maxCoeff();
  for (Index j = 0; j < mine.cols(); ++j)
    ASSERT_NEAR(values(0, j), expected(0, j), 1e-12 * peak) << "point " << j << " of rank " << rank;
  double farthest = 0;
  for (int r = 0; r < size; ++r) {
    const Points theirs = points_of(r);
    farthest = std::max(
        farthest, PointMap::BarycentricInTets(mesh->nodes, mesh->tets, theirs).max_distance());
  }
  EXPECT_NEAR(interpolation->max_distance(), farthest, 1e-15);
  EXPECT_GT(farthest, 0.02);  // the far point: sqrt(20² + 10² + 18²) mm from the corner

  // A marker in the field is kept, not blended: V of -80 mV (rest) marked as no data.
  interpolation->Interpolate(tissue->FindField("V"), values, -80.0);
  Eigen::MatrixXd marked(1, mine.cols());
  serial.ApplyMarked(volts, marked, -80.0);
  for (Index j = 0; j < mine.cols(); ++j)
    ASSERT_NEAR(values(0, j), marked(0, j), 1e-12 * peak) << "point " << j << " of rank " << rank;

  // A point that is not finite is refused on every rank.
  Points bad = mine;
  if (rank == 0) bad(1, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)tissue->InterpolateAtPoints(bad), InputError);
}

// A barycentric FieldCopy of V (2 kPa/mV) from the tissue made in blocks onto a muscle on
// another, coarser mesh that sticks out of it, made in blocks too (so cut differently) or whole
// on every rank: each rank's items get the whole box's interpolation of V at them (the nearest
// point of the box outside it), with no gather; a coordinator takes it. A "direct" copy between
// them is refused.
// The tissue made in blocks after 6 ms, and V of the whole box (from the tissue split from it)
// interpolated at the items of a muscle on the other box: its nodes or its tets' centroids.
struct TwoMeshes {
  std::shared_ptr<const Mesh> mesh = Box();
  std::shared_ptr<const Mesh> other =
      std::make_shared<Mesh>(MakeTetBox(kOtherLo, kOtherHi, kOtherCells));
  std::unique_ptr<WholeDomainView> tissue = TissueInBlocks();
  Eigen::MatrixXd volts;

  TwoMeshes() {
    const auto whole_tissue = SplitTissue(mesh);
    for (int s = 0; s < 60; ++s) {
      EXPECT_TRUE(tissue->Step(1e-4).ok());  // 6 ms
      EXPECT_TRUE(whole_tissue->Step(1e-4).ok());
    }
    volts = Read(*whole_tissue, "V");
  }
  [[nodiscard]] Eigen::MatrixXd VAtOtherItems(bool at_nodes) const {
    const Points at =
        at_nodes ? other->nodes : ItemRestPositions(*Muscle(other, false), FieldLocation::kElement);
    Eigen::MatrixXd out(1, at.cols());
    PointMap::BarycentricInTets(mesh->nodes, mesh->tets, at).Apply(volts, out);
    return out;
  }
};

TEST(SplitCoupling, ABarycentricCopyJoinsObjectsSplitDifferently) {
  TwoMeshes two;
  std::unique_ptr<WholeDomainView>& tissue = two.tissue;
  const FieldId v = tissue->FindField("V");
  using Mapping = FieldCopy::Mapping;
  for (const char* field : {"nodal_active_tension", "active_tension"}) {
    SCOPED_TRACE(field);
    const bool at_nodes = std::string(field) == "nodal_active_tension";
    // The whole box's interpolation at every item of the other mesh, scaled to Pa.
    const Eigen::MatrixXd expected = 2000.0 * two.VAtOtherItems(at_nodes);
    const double peak = expected.cwiseAbs().maxCoeff();
    ASSERT_GT(peak, 1e5);

    std::unique_ptr<WholeDomainView> split_muscle =
        MuscleInBlocks(BoxInBlocks(kOtherLo, kOtherHi, kOtherCells));
    std::unique_ptr<SimObject> whole_muscle = Muscle(two.other, false);
    EXPECT_FALSE(SplitAlike(*tissue, *split_muscle));
    FieldCopy onto_parts("copy", *tissue, v, *split_muscle, split_muscle->FindField(field),
                         Mapping::kAuto, 2, "kPa/mV");
    FieldCopy onto_whole("copy", *tissue, v, *whole_muscle, whole_muscle->FindField(field),
                         Mapping::kBarycentric, 2, "kPa/mV");
    EXPECT_EQ(onto_parts.mapping(), Mapping::kBarycentric);
    EXPECT_TRUE(onto_parts.couples_parts());
    EXPECT_TRUE(onto_whole.couples_parts());
    const std::int64_t reads_before = tissue->whole_field_reads();
    ASSERT_TRUE(onto_parts.Fire(0).ok());
    ASSERT_TRUE(onto_whole.Fire(0).ok());
    EXPECT_EQ(tissue->whole_field_reads(), reads_before);

    const Eigen::MatrixXd local = Read(split_muscle->local_part(), field);
    const std::span<const int> items =
        at_nodes ? split_muscle->whole_nodes_of_part() : split_muscle->whole_tets_of_part();
    ASSERT_EQ(static_cast<std::size_t>(local.cols()), items.size());
    for (Index i = 0; i < local.cols(); ++i)
      ASSERT_NEAR(local(0, i), expected(0, items[static_cast<std::size_t>(i)]), 1e-12 * peak)
          << "whole item " << items[static_cast<std::size_t>(i)];
    const Eigen::MatrixXd everywhere = Read(*whole_muscle, field);
    ASSERT_EQ(everywhere.cols(), expected.cols());
    EXPECT_LE((everywhere - expected).cwiseAbs().maxCoeff(), 1e-12 * peak);
  }

  // A coordinator takes the copy between the two objects made in blocks.
  Coordinator coupled;
  std::unique_ptr<WholeDomainView> muscle =
      MuscleInBlocks(BoxInBlocks(kOtherLo, kOtherHi, kOtherCells));
  SimObject* source = tissue.get();
  SimObject* target = muscle.get();
  coupled.AddObject(std::move(tissue), 1e-4);
  coupled.AddObject(std::move(muscle), 1e-4);
  coupled.AddConnector(
      std::make_unique<FieldCopy>("copy", *source, v, *target, target->FindField("active_tension"),
                                  Mapping::kBarycentric, 2, "kPa/mV"),
      1);
  EXPECT_NO_THROW(coupled.Prepare(1e-4));
  // Item for item between them is not a thing: refused on every rank alike.
  try {
    FieldCopy direct("copy", *source, v, *target, target->FindField("nodal_active_tension"),
                     Mapping::kDirect, 2, "kPa/mV");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("split differently"), std::string::npos) << e.what();
  }
}

// The whole source item nearest to each of `at`'s points: the smallest distance, then the
// lowest index (PointMap::Nearest's rule).
std::vector<Index> NearestItems(const Points& sources, const Points& at) {
  std::vector<Index> out(static_cast<std::size_t>(at.cols()));
  for (Index j = 0; j < at.cols(); ++j) {
    double best = std::numeric_limits<double>::infinity();
    for (Index i = 0; i < sources.cols(); ++i) {
      const double d = (sources.col(i) - at.col(j)).norm();
      if (d < best) {
        best = d;
        out[static_cast<std::size_t>(j)] = i;
      }
    }
  }
  return out;
}

// A nearest-item FieldCopy joins objects split any way, with no gather, and gives each item the
// value of the whole source's nearest item (the lowest index on a tie) bit for bit:
// - V of the tissue made in blocks (2 kPa/mV) onto the other mesh's muscle, made in blocks or
//   whole on every rank, at its nodes and at its tets' centroids;
// - the tension of that split muscle's tets onto the tets of a muscle on the tissue's box (a
//   tet field's items are the centroids);
// - a part-only muscle's boundary positions (at rest) onto another's node forces (1 N/m):
//   each node gets the position of the whole boundary's vertex nearest to it.
// Points halfway between neighbouring nodes take the lower one (ties, on the parts' cuts too). A
// coordinator takes a nearest copy between objects made in blocks. A view holding its whole mesh
// has its boundary fields whole, and its parts do not answer for them.
TEST(SplitCoupling, ANearestCopyJoinsObjectsSplitAnyWay) {
  TwoMeshes two;
  std::unique_ptr<WholeDomainView>& tissue = two.tissue;
  const FieldId v = tissue->FindField("V");
  using Mapping = FieldCopy::Mapping;
  const Points other_centroids =
      ItemRestPositions(*Muscle(two.other, false), FieldLocation::kElement);
  std::unique_ptr<WholeDomainView> tensed;  // the split muscle on the other mesh, tensed
  Eigen::MatrixXd tension;                  // its tets' tension, whole
  for (const char* field : {"nodal_active_tension", "active_tension"}) {
    SCOPED_TRACE(field);
    const bool at_nodes = std::string(field) == "nodal_active_tension";
    const Points& at = at_nodes ? two.other->nodes : other_centroids;
    const std::vector<Index> nearest = NearestItems(two.mesh->nodes, at);
    const PointMap serial = PointMap::Nearest(two.mesh->nodes, at);
    for (Index j = 0; j < at.cols(); ++j)
      ASSERT_EQ(serial.indices()(0, j), nearest[static_cast<std::size_t>(j)]) << "item " << j;

    std::unique_ptr<WholeDomainView> split_muscle =
        MuscleInBlocks(BoxInBlocks(kOtherLo, kOtherHi, kOtherCells));
    std::unique_ptr<SimObject> whole_muscle = Muscle(two.other, false);
    FieldCopy onto_parts("copy", *tissue, v, *split_muscle, split_muscle->FindField(field),
                         Mapping::kNearest, 2, "kPa/mV");
    FieldCopy onto_whole("copy", *tissue, v, *whole_muscle, whole_muscle->FindField(field),
                         Mapping::kNearest, 2, "kPa/mV");
    EXPECT_TRUE(onto_parts.couples_parts());
    EXPECT_TRUE(onto_whole.couples_parts());
    const std::int64_t reads_before = tissue->whole_field_reads();
    ASSERT_TRUE(onto_parts.Fire(0).ok());
    ASSERT_TRUE(onto_whole.Fire(0).ok());
    EXPECT_EQ(tissue->whole_field_reads(), reads_before);
    const double factor = onto_parts.factor();
    EXPECT_NEAR(factor, 2000, 1e-9);
    Eigen::MatrixXd expected(1, at.cols());
    for (Index j = 0; j < at.cols(); ++j)
      expected(0, j) = factor * two.volts(0, nearest[static_cast<std::size_t>(j)]);
    EXPECT_GT(expected.cwiseAbs().maxCoeff(), 1e5);

    const Eigen::MatrixXd local = Read(split_muscle->local_part(), field);
    const std::span<const int> items =
        at_nodes ? split_muscle->whole_nodes_of_part() : split_muscle->whole_tets_of_part();
    ASSERT_EQ(static_cast<std::size_t>(local.cols()), items.size());
    for (Index i = 0; i < local.cols(); ++i)
      ASSERT_EQ(local(0, i), expected(0, items[static_cast<std::size_t>(i)]))
          << "whole item " << items[static_cast<std::size_t>(i)];
    EXPECT_EQ(Read(*whole_muscle, field), expected);
    if (!at_nodes) {
      tensed = std::move(split_muscle);
      tension = expected;
    }
  }

  {  // a split muscle's tet field onto the tets of another split muscle, on the tissue's box
    std::unique_ptr<WholeDomainView> target = MuscleInBlocks();
    FieldCopy copy("copy", *tensed, tensed->FindField("active_tension"), *target,
                   target->FindField("active_tension"), Mapping::kNearest, 1);
    EXPECT_TRUE(copy.couples_parts());
    const std::int64_t reads_before = tensed->whole_field_reads();
    ASSERT_TRUE(copy.Fire(0).ok());
    EXPECT_EQ(tensed->whole_field_reads(), reads_before);
    const Points centroids = ItemRestPositions(*Muscle(two.mesh, false), FieldLocation::kElement);
    const std::vector<Index> nearest = NearestItems(other_centroids, centroids);
    const Eigen::MatrixXd local = Read(target->local_part(), "active_tension");
    const std::span<const int> tets = target->whole_tets_of_part();
    for (Index i = 0; i < local.cols(); ++i) {
      const auto whole = static_cast<std::size_t>(tets[static_cast<std::size_t>(i)]);
      ASSERT_EQ(local(0, i), tension(0, nearest[whole])) << "whole tet " << whole;
    }
  }

  {  // a part-only muscle's boundary positions onto another's node forces
    std::unique_ptr<WholeDomainView> source =
        MuscleInBlocks(BoxInBlocks(kOtherLo, kOtherHi, kOtherCells));
    std::unique_ptr<WholeDomainView> target = MuscleInBlocks();
    FieldCopy copy("copy", *source, source->FindField("boundary_position"), *target,
                   target->FindField("external_force"), Mapping::kNearest, 1, "N/m");
    EXPECT_TRUE(copy.couples_parts());
    ASSERT_TRUE(copy.Fire(0).ok());
    Points vertices;
    MakeBoundary(*two.other).Gather(two.other->nodes, vertices);
    const std::vector<Index> nearest = NearestItems(vertices, two.mesh->nodes);
    const Eigen::MatrixXd local = Read(target->local_part(), "external_force");
    const std::span<const int> nodes = target->whole_nodes_of_part();
    ASSERT_EQ(static_cast<std::size_t>(local.cols()), nodes.size());
    for (Index i = 0; i < local.cols(); ++i) {
      const auto whole = static_cast<std::size_t>(nodes[static_cast<std::size_t>(i)]);
      ASSERT_EQ(Vec3(local.col(i)), Vec3(vertices.col(nearest[whole]))) << "whole node " << whole;
    }
  }

  {  // ties: points halfway between neighbouring nodes (on parts' cuts too) take the lower node
    Points halfway(3, two.mesh->num_nodes() - 1);
    for (Index n = 0; n + 1 < two.mesh->num_nodes(); ++n)
      halfway.col(n) = 0.5 * (two.mesh->nodes.col(n) + two.mesh->nodes.col(n + 1));
    const std::vector<Index> nearest = NearestItems(two.mesh->nodes, halfway);
    int ties = 0;
    for (Index n = 0; n < halfway.cols(); ++n)
      ties += (two.mesh->nodes.col(n) - halfway.col(n)).norm() ==
              (two.mesh->nodes.col(n + 1) - halfway.col(n)).norm();
    EXPECT_GT(ties, 100);
    const auto parts = tissue->NearestAtPoints(FieldLocation::kNode, halfway);
    Eigen::MatrixXd values(1, halfway.cols());
    parts->Interpolate(v, values, std::nullopt);
    for (Index n = 0; n < halfway.cols(); ++n)
      ASSERT_EQ(values(0, n), two.volts(0, nearest[static_cast<std::size_t>(n)])) << "point " << n;
  }

  // A coordinator takes the copy between the tissue and a muscle made in blocks.
  Coordinator coupled;
  std::unique_ptr<WholeDomainView> muscle =
      MuscleInBlocks(BoxInBlocks(kOtherLo, kOtherHi, kOtherCells));
  SimObject* source = tissue.get();
  SimObject* target = muscle.get();
  coupled.AddObject(std::move(tissue), 1e-4);
  coupled.AddObject(std::move(muscle), 1e-4);
  coupled.AddConnector(
      std::make_unique<FieldCopy>("copy", *source, v, *target, target->FindField("active_tension"),
                                  Mapping::kNearest, 2, "kPa/mV"),
      1);
  EXPECT_NO_THROW(coupled.Prepare(1e-4));

  const auto whole_view = Muscle(two.mesh, true);
  EXPECT_THROW((void)dynamic_cast<const PartitionedObject&>(*whole_view)
                   .NearestAtPoints(FieldLocation::kBoundaryVertex, two.mesh->nodes),
               InputError);
}

// The excitation–contraction coupling between the tissue made in blocks and a muscle on another,
// coarser mesh that sticks out of it, made in blocks too (so cut differently): every muscle node
// and tet of every part gets the twitch law at the whole box's interpolation of V there, with
// no gather.
TEST(SplitCoupling, ExcitationContractionJoinsObjectsOnTwoMeshes) {
  TwoMeshes two;
  std::unique_ptr<WholeDomainView>& tissue = two.tissue;
  for (const char* field : {"nodal_active_tension", "active_tension"}) {
    SCOPED_TRACE(field);
    const bool at_nodes = std::string(field) == "nodal_active_tension";
    const Eigen::MatrixXd v_there = two.VAtOtherItems(at_nodes);
    std::unique_ptr<WholeDomainView> muscle =
        MuscleInBlocks(BoxInBlocks(kOtherLo, kOtherHi, kOtherCells));
    ExcitationContraction ec("ec", *tissue, tissue->FindField("V"), *muscle,
                             muscle->FindField(field), kTwitch);
    EXPECT_TRUE(ec.couples_parts());
    const std::int64_t reads_before = tissue->whole_field_reads();
    for (double t : {0.0, 0.004}) ASSERT_TRUE(ec.Fire(t).ok());
    EXPECT_EQ(tissue->whole_field_reads(), reads_before);
    const Eigen::MatrixXd local = Read(muscle->local_part(), field);
    const std::span<const int> items =
        at_nodes ? muscle->whole_nodes_of_part() : muscle->whole_tets_of_part();
    ASSERT_EQ(static_cast<std::size_t>(local.cols()), items.size());
    double peak = 0;
    for (Index i = 0; i < local.cols(); ++i) {
      const int item = items[static_cast<std::size_t>(i)];
      ASSERT_NEAR(local(0, i), Twitch(v_there(0, item), 0.0, 0.004), 1e-9) << "whole item " << item;
      peak = std::max(peak, local(0, i));
    }
    MPI_Allreduce(MPI_IN_PLACE, &peak, 1, MPI_DOUBLE, MPI_MAX, World());
    EXPECT_GT(peak, 1e3);  // Pa: some of the muscle lies in the excited tissue
  }
}

}  // namespace
}  // namespace gipsi
