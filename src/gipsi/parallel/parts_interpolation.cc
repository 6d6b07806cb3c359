/// @file
/// Values of a split object's node field at points each rank chooses (parts_interpolation.h).
/// Each rank locates the points others send it once per round; the part chosen for a point
/// keeps the weights it found then.

#include "gipsi/parallel/parts_interpolation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/spatial_grid.h"
#include "gipsi/parallel/mesh_partition_detail.h"

namespace gipsi {
namespace {

using Point3 = std::array<double, 3>;

// A part's bounding box: its lowest and highest corners.
struct Box {
  Point3 lo, hi;
};

double BoxDistance(const Box& box, const Point3& p) {
  double squared = 0;
  for (int k = 0; k < 3; ++k) {
    const double out = std::max({box.lo[k] - p[k], 0.0, p[k] - box.hi[k]});
    squared += out * out;
  }
  return std::sqrt(squared);
}

// The points as a 3 × n matrix.
Points AsPoints(const std::vector<Point3>& points) {
  Points out(3, static_cast<Index>(points.size()));
  for (std::size_t j = 0; j < points.size(); ++j)
    for (int k = 0; k < 3; ++k)
      out(k, static_cast<Index>(j)) = points[j][static_cast<std::size_t>(k)];
  return out;
}

// The points located on the part's tets, and how far each lies from the point its weights
// reproduce (0 inside, up to rounding).
PointMap Locate(const Mesh& mesh, const std::vector<Point3>& points,
                std::vector<double>& distance) {
  const Points at = AsPoints(points);
  PointMap map = PointMap::BarycentricInTets(mesh.nodes, mesh.tets, at);
  distance.resize(points.size());
  for (Index j = 0; j < at.cols(); ++j) {
    Vec3 reproduced = Vec3::Zero();
    for (int k = 0; k < 4; ++k)
      reproduced += map.weights()(k, j) * mesh.nodes.col(map.indices()(k, j));
    distance[static_cast<std::size_t>(j)] = (reproduced - at.col(j)).norm();
  }
  return map;
}

// Which point of a round's requests a rank was chosen for: the round and the point's position
// among those the asking rank sent it then.
struct Choice {
  int round = 0;
  int position = 0;
};

// A part's answer for a point: how far the point lies from what the part found, and the key
// that settles a tie (the answering rank for a barycentric point, the item's whole index for
// a nearest one: the lowest wins).
struct Reply {
  double distance = 0;
  std::int64_t key = 0;
};

// What a part answers with: barycentric weights in its tets, its nearest item, or barycentric
// weights on its nearest boundary face.
enum class Kind { kTets, kNearest, kTriangles };

// How this rank's part answers for points: the box of what it can answer from, and its answer
// (the part field's columns and weights for each point, with its Reply).
struct Locator {
  Kind kind = Kind::kTets;
  Box box;
  std::function<PointMap(const std::vector<Point3>&, std::vector<Reply>&)> locate;
};

// Where a part boundary's vertices are owned (BoundaryInterpolation::Spread): each vertex
// whose node another rank owns, that rank and the node's global number; on the owner, the
// boundary vertex of each owned node (-1 for a node off the boundary).
struct VertexOwners {
  std::vector<int> owner;            // per part boundary vertex: -1 when this rank's
  std::vector<std::int64_t> global;  // per part boundary vertex: its node's global number
  std::vector<int> vertex_of_owned;  // per owned node
  std::int64_t first_owned = 0;
};

// A shared vertex's sum sent to its owner.
struct VertexSum {
  std::int64_t global = 0;
  std::array<double, 3> value{};
};

// The box of the columns of `at` (empty: lowest corner +inf, highest -inf, at infinite
// distance from every point).
Box BoxOf(const Points& at) {
  Box box;
  for (std::size_t k = 0; k < 3; ++k) {
    const auto row = static_cast<Index>(k);
    box.lo[k] = at.cols() > 0 ? at.row(row).minCoeff() : std::numeric_limits<double>::infinity();
    box.hi[k] = at.cols() > 0 ? at.row(row).maxCoeff() : -std::numeric_limits<double>::infinity();
  }
  return box;
}

// One class for the three kinds; Spread only for kTriangles (with the vertices' owners).
class Interpolation final : public BoundaryInterpolation {
 public:
  // `share` is empty for a nearest item (each item is on one rank only) and on the boundary
  // (a solid's shared nodes hold their owners' values after every step).
  Interpolation(const SimObject& part, Locator locator, const Points& points, MPI_Comm comm,
                std::function<FieldId(FieldId)> part_field,
                std::function<void(Eigen::Ref<Eigen::MatrixXd>)> share,
                std::optional<VertexOwners> owners = std::nullopt);

  [[nodiscard]] Index num_points() const override { return num_points_; }
  [[nodiscard]] double max_distance() const override { return max_distance_; }
  [[nodiscard]] std::span<const double> distances() const override { return distances_; }
  void Interpolate(FieldId id, Eigen::Ref<Eigen::MatrixXd> out,
                   std::optional<double> no_data) const override;
  void Spread(const Eigen::Ref<const Eigen::MatrixXd>& at_points,
              Eigen::Ref<Eigen::MatrixXd> out) const override;

 private:
  // The nearest part found so far for each of this rank's points: its rank, and where the point
  // was in what that rank was sent (the round, the position among the points sent to it then).
  struct Nearest {
    double distance = std::numeric_limits<double>::infinity();
    std::int64_t key = std::numeric_limits<std::int64_t>::max();
    int rank = -1;
    Choice choice;
  };
  // What a rank located for the others in one round: the points' weights on its part, in the
  // order they came, and where each sender's points begin.
  struct Located {
    PointMap map;
    std::vector<int> begin;
  };
  // Sends `to[r]` (points `index[r]` of this rank's) to rank r, which locates them on its part
  // and answers (Reply); keeps each point's best answer. Returns what this rank located for the
  // others. Collective.
  Located Ask(int round, const std::vector<std::vector<Point3>>& to,
              const std::vector<std::vector<Index>>& index, std::vector<Nearest>& nearest) const;

  const SimObject& part_;
  Locator locator_;
  MPI_Comm comm_;
  std::function<FieldId(FieldId)> part_field_;
  std::function<void(Eigen::Ref<Eigen::MatrixXd>)> share_;
  std::optional<VertexOwners> owners_;
  Index num_points_ = 0;
  double max_distance_ = 0;
  std::vector<double> distances_;  // each of this rank's points' distance
  // The points other ranks asked of this part (in rank order), and how many each rank asked.
  PointMap answer_;
  std::vector<int> answer_counts_;
  // The points this rank asked of each rank (in rank order: the point each arriving value is
  // for), and how many.
  std::vector<Index> asked_;
  std::vector<int> asked_counts_;
  // Buffers of Interpolate and Spread.
  mutable Eigen::MatrixXd source_, answers_, received_;
  mutable std::vector<int> send_counts_, send_offsets_, receive_counts_, receive_offsets_;
};

Interpolation::Interpolation(const SimObject& part, Locator locator, const Points& points,
                             MPI_Comm comm, std::function<FieldId(FieldId)> part_field,
                             std::function<void(Eigen::Ref<Eigen::MatrixXd>)> share,
                             std::optional<VertexOwners> owners)
    : part_(part),
      locator_(std::move(locator)),
      comm_(comm),
      part_field_(std::move(part_field)),
      share_(std::move(share)),
      owners_(std::move(owners)),
      num_points_(points.cols()) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  const auto ranks = static_cast<std::size_t>(size);
  int bad = points.allFinite() ? 0 : 1;
  MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT, MPI_MAX, comm);
  if (bad != 0) throw InputError("a point to interpolate the split object at is not finite");

  // Every part's box, and a slack of 1e-9 of the whole box's diagonal for points that lie on a
  // box's side up to rounding.
  std::vector<Box> boxes(ranks);
  MPI_Allgather(&locator_.box, 6, MPI_DOUBLE, boxes.data(), 6, MPI_DOUBLE, comm);
  Box all{{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
           std::numeric_limits<double>::infinity()},
          {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
           -std::numeric_limits<double>::infinity()}};
  for (const Box& box : boxes)
    for (std::size_t k = 0; k < 3; ++k) {
      all.lo[k] = std::min(all.lo[k], box.lo[k]);
      all.hi[k] = std::max(all.hi[k], box.hi[k]);
    }
  if (!(all.lo[0] <= all.hi[0])) {  // no part has anything to answer from (every rank sees it)
    auto total = static_cast<std::int64_t>(num_points_);
    MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_INT64_T, MPI_SUM, comm);
    if (total > 0)
      throw InputError(
          fmt::format("the split object has no items to take {} points' values from", total));
    answer_counts_.assign(ranks, 0);  // nothing to send or receive at a firing
    asked_counts_.assign(ranks, 0);
    return;
  }
  const double slack =
      1e-9 * std::hypot(all.hi[0] - all.lo[0], all.hi[1] - all.lo[1], all.hi[2] - all.lo[2]);

  auto point = [&points](Index j) { return Point3{points(0, j), points(1, j), points(2, j)}; };
  std::vector<Nearest> nearest(static_cast<std::size_t>(num_points_));
  // Round 0 asks those parts. Round 1 asks every other part whose box is no farther than the
  // best answer: for a barycentric point only if no part holds it (a point outside the domain
  // goes to the part nearest to it, or off the boundary to the nearest face), for the nearest
  // item always (a neighbouring part's item may be nearer than any of the holding part's).
  const bool bounded = locator_.kind != Kind::kTets;
  std::array<Located, 2> located;
  std::vector<double> d(ranks);
  for (const int round : {0, 1}) {
    std::vector<std::vector<Point3>> to(ranks);
    std::vector<std::vector<Index>> index(ranks);
    for (Index j = 0; j < num_points_; ++j) {
      const Nearest& found = nearest[static_cast<std::size_t>(j)];
      if (round == 1 && locator_.kind != Kind::kNearest && found.distance <= slack) continue;
      const Point3 p = point(j);
      for (std::size_t r = 0; r < ranks; ++r) d[r] = BoxDistance(boxes[r], p);
      // Round 0 asks the parts whose boxes hold the point; for the nearest item or face also
      // the nearest box's (the lowest rank on a tie), so that every point has an answer to
      // bound round 1 by (a point far from the boundary then asks a few parts, not all).
      const auto closest =
          static_cast<std::size_t>(std::min_element(d.begin(), d.end()) - d.begin());
      for (std::size_t r = 0; r < ranks; ++r) {
        const bool first = d[r] <= slack || (bounded && r == closest);
        const bool ask =
            round == 0 ? first : !first && std::isfinite(d[r]) && d[r] <= found.distance;
        if (!ask) continue;
        to[r].push_back(p);
        index[r].push_back(j);
      }
    }
    located[static_cast<std::size_t>(round)] = Ask(round, to, index, nearest);
  }

  // Each point's part keeps its weights, picked from what it located.
  std::vector<std::vector<Choice>> to(ranks);
  std::vector<std::vector<Index>> index(ranks);
  for (Index j = 0; j < num_points_; ++j) {
    const Nearest& found = nearest[static_cast<std::size_t>(j)];
    GIPSI_CHECK(found.rank >= 0 && found.rank < size, "a point no part was asked for");
    max_distance_ = std::max(max_distance_, found.distance);
    distances_.push_back(found.distance);
    to[static_cast<std::size_t>(found.rank)].push_back(found.choice);
    index[static_cast<std::size_t>(found.rank)].push_back(j);
  }
  const detail::Received<Choice> got = detail::Exchange(to, comm);
  const auto count = static_cast<Index>(got.items.size());
  Eigen::Matrix4Xi nodes(4, count);
  Eigen::Matrix4Xd weights(4, count);
  std::size_t k = 0;
  for (std::size_t r = 0; r < ranks; ++r)
    for (int c = 0; c < got.counts[r]; ++c, ++k) {
      const Choice& choice = got.items[k];
      const Located& from = located[static_cast<std::size_t>(choice.round)];
      const Index column = from.begin[r] + choice.position;
      nodes.col(static_cast<Index>(k)) = from.map.indices().col(column);
      weights.col(static_cast<Index>(k)) = from.map.weights().col(column);
    }
  answer_ = PointMap::FromWeights(std::move(nodes), std::move(weights), 0);
  answer_counts_ = got.counts;
  asked_counts_.resize(ranks);
  for (std::size_t r = 0; r < ranks; ++r) {
    asked_counts_[r] = static_cast<int>(index[r].size());
    asked_.insert(asked_.end(), index[r].begin(), index[r].end());
  }
  MPI_Allreduce(MPI_IN_PLACE, &max_distance_, 1, MPI_DOUBLE, MPI_MAX, comm);
}

Interpolation::Located Interpolation::Ask(int round, const std::vector<std::vector<Point3>>& to,
                                          const std::vector<std::vector<Index>>& index,
                                          std::vector<Nearest>& nearest) const {
  const detail::Received<Point3> got = detail::Exchange(to, comm_);
  std::vector<Reply> replies;
  Located located{locator_.locate(got.items, replies), {}};
  std::vector<std::vector<Reply>> reply(to.size());
  std::size_t k = 0;
  for (std::size_t r = 0; r < to.size(); ++r) {
    located.begin.push_back(static_cast<int>(k));
    for (int c = 0; c < got.counts[r]; ++c) reply[r].push_back(replies[k++]);
  }
  const detail::Received<Reply> back = detail::Exchange(reply, comm_);
  k = 0;
  for (std::size_t r = 0; r < to.size(); ++r) {
    GIPSI_CHECK(back.counts[r] == static_cast<int>(index[r].size()), "answers lost");
    for (std::size_t position = 0; position < index[r].size(); ++position) {
      Nearest& found = nearest[static_cast<std::size_t>(index[r][position])];
      const Reply& answer = back.items[k++];
      if (answer.distance < found.distance ||
          (answer.distance == found.distance && answer.key < found.key))
        found = {
            answer.distance, answer.key, static_cast<int>(r), {round, static_cast<int>(position)}};
    }
  }
  return located;
}

void Interpolation::Interpolate(FieldId id, Eigen::Ref<Eigen::MatrixXd> out,
                                std::optional<double> no_data) const {
  const FieldId field = part_field_(id);
  const FieldInfo& info = part_.field_info(field);
  GIPSI_CHECK(locator_.kind == Kind::kNearest ||
                  info.location == (locator_.kind == Kind::kTets ? FieldLocation::kNode
                                                                 : FieldLocation::kBoundaryVertex),
              "field '{}' is not a {} field", info.name,
              locator_.kind == Kind::kTets ? "node" : "boundary-vertex");
  const Index components = info.components;
  GIPSI_CHECK(out.rows() == components && out.cols() == num_points_,
              "interpolation into {}×{} values, expected {}×{}", out.rows(), out.cols(), components,
              num_points_);
  source_.resize(components, part_.FieldCount(field));
  part_.ReadField(field, source_);
  if (share_) share_(source_);
  answers_.resize(components, answer_.num_targets());
  if (locator_.kind == Kind::kNearest) {
    answer_.Apply(source_, answers_);  // the item's value: a marker stays a marker
  } else if (no_data) {
    answer_.ApplyMarked(source_, answers_, *no_data);
  } else {
    answer_.Apply(source_, answers_);
    if (locator_.kind == Kind::kTets)
      part_.CorrectInterpolated(field, answer_.indices(), answer_.weights(), answers_);
  }
  const std::size_t ranks = answer_counts_.size();
  send_counts_.resize(ranks);
  send_offsets_.assign(ranks, 0);
  receive_counts_.resize(ranks);
  receive_offsets_.assign(ranks, 0);
  const auto width = static_cast<std::int64_t>(components);
  GIPSI_CHECK(width * answers_.cols() < std::int64_t{1} << 31 &&
                  width * static_cast<std::int64_t>(asked_.size()) < std::int64_t{1} << 31,
              "an interpolation past 2^31 values per rank");
  for (std::size_t r = 0; r < ranks; ++r) {
    send_counts_[r] = static_cast<int>(width * answer_counts_[r]);
    receive_counts_[r] = static_cast<int>(width * asked_counts_[r]);
  }
  std::partial_sum(send_counts_.begin(), send_counts_.end() - 1, send_offsets_.begin() + 1);
  std::partial_sum(receive_counts_.begin(), receive_counts_.end() - 1,
                   receive_offsets_.begin() + 1);
  received_.resize(components, static_cast<Index>(asked_.size()));
  MPI_Alltoallv(answers_.data(), send_counts_.data(), send_offsets_.data(), MPI_DOUBLE,
                received_.data(), receive_counts_.data(), receive_offsets_.data(), MPI_DOUBLE,
                comm_);
  for (std::size_t k = 0; k < asked_.size(); ++k)
    out.col(asked_[k]) = received_.col(static_cast<Index>(k));
}

void Interpolation::Spread(const Eigen::Ref<const Eigen::MatrixXd>& at_points,
                           Eigen::Ref<Eigen::MatrixXd> out) const {
  GIPSI_CHECK(locator_.kind == Kind::kTriangles && owners_, "a spread off the boundary");
  const auto vertices = static_cast<Index>(owners_->owner.size());
  GIPSI_CHECK(at_points.rows() == 3 && at_points.cols() == num_points_ && out.rows() == 3 &&
                  out.cols() == vertices,
              "a spread of {}×{} values into {}×{}, expected 3×{} into 3×{}", at_points.rows(),
              at_points.cols(), out.rows(), out.cols(), num_points_, vertices);
  // Each point's value back to the rank that answered for it: Interpolate's exchange reversed.
  const std::size_t ranks = answer_counts_.size();
  send_counts_.resize(ranks);
  send_offsets_.assign(ranks, 0);
  receive_counts_.resize(ranks);
  receive_offsets_.assign(ranks, 0);
  for (std::size_t r = 0; r < ranks; ++r) {
    send_counts_[r] = 3 * asked_counts_[r];
    receive_counts_[r] = 3 * answer_counts_[r];
  }
  std::partial_sum(send_counts_.begin(), send_counts_.end() - 1, send_offsets_.begin() + 1);
  std::partial_sum(receive_counts_.begin(), receive_counts_.end() - 1,
                   receive_offsets_.begin() + 1);
  received_.resize(3, static_cast<Index>(asked_.size()));
  for (std::size_t k = 0; k < asked_.size(); ++k)
    received_.col(static_cast<Index>(k)) = at_points.col(asked_[k]);
  answers_.resize(3, answer_.num_targets());
  MPI_Alltoallv(received_.data(), send_counts_.data(), send_offsets_.data(), MPI_DOUBLE,
                answers_.data(), receive_counts_.data(), receive_offsets_.data(), MPI_DOUBLE,
                comm_);
  // Onto the faces' vertices, in the order the points came (rank, then position).
  out.setZero();
  const Eigen::Matrix4Xi& index = answer_.indices();
  const Eigen::Matrix4Xd& weight = answer_.weights();
  for (Index k = 0; k < answers_.cols(); ++k)
    for (int s = 0; s < 4; ++s)
      if (weight(s, k) != 0) out.col(index(s, k)) += weight(s, k) * answers_.col(k);
  // The shared vertices' sums to their owners, which add them in rank order.
  std::vector<std::vector<VertexSum>> to(ranks);
  for (Index v = 0; v < vertices; ++v) {
    const int owner = owners_->owner[static_cast<std::size_t>(v)];
    if (owner < 0 || out.col(v).isZero(0)) continue;
    to[static_cast<std::size_t>(owner)].push_back(
        {owners_->global[static_cast<std::size_t>(v)], {out(0, v), out(1, v), out(2, v)}});
    out.col(v).setZero();
  }
  const detail::Received<VertexSum> got = detail::Exchange(to, comm_);
  for (const VertexSum& sum : got.items) {
    const std::int64_t node = sum.global - owners_->first_owned;
    GIPSI_CHECK(node >= 0 && node < static_cast<std::int64_t>(owners_->vertex_of_owned.size()),
                "a vertex's sum sent to a rank that does not own its node");
    const int v = owners_->vertex_of_owned[static_cast<std::size_t>(node)];
    GIPSI_CHECK(v >= 0, "a vertex's sum for a node off the owner's boundary");
    for (int k = 0; k < 3; ++k) out(k, v) += sum.value[static_cast<std::size_t>(k)];
  }
}

}  // namespace

std::unique_ptr<PartsInterpolation> MakePartsInterpolation(
    const SimObject& part, const MeshPart& mesh_part, const Points& points, MPI_Comm comm,
    std::function<FieldId(FieldId)> part_field,
    std::function<void(Eigen::Ref<Eigen::MatrixXd>)> share) {
  const Mesh& mesh = *mesh_part.mesh;
  GIPSI_CHECK(mesh.num_nodes() > 0, "a part without nodes");
  Locator locator;
  locator.box = BoxOf(mesh.nodes);
  const int rank = mesh_part.rank;
  locator.locate = [&mesh, rank](const std::vector<Point3>& at, std::vector<Reply>& replies) {
    std::vector<double> distance;
    PointMap map = Locate(mesh, at, distance);
    replies.resize(at.size());
    for (std::size_t j = 0; j < at.size(); ++j) replies[j] = {distance[j], rank};
    return map;
  };
  return std::make_unique<Interpolation>(part, std::move(locator), points, comm,
                                         std::move(part_field), std::move(share));
}

std::unique_ptr<PartsInterpolation> MakePartsNearest(const SimObject& part, NearestItems items,
                                                     const Points& points, MPI_Comm comm,
                                                     std::function<FieldId(FieldId)> part_field) {
  GIPSI_CHECK(items.positions.rows() == 3 &&
                  static_cast<std::size_t>(items.positions.cols()) == items.keys.size() &&
                  items.keys.size() == items.columns.size(),
              "nearest items: {} positions, {} keys, {} columns", items.positions.cols(),
              items.keys.size(), items.columns.size());
  // In the order of their keys, so that the grid's lowest item on a tie is the lowest key.
  std::vector<std::size_t> order(items.keys.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&items](std::size_t a, std::size_t b) { return items.keys[a] < items.keys[b]; });
  NearestItems sorted;
  sorted.positions.resize(3, items.positions.cols());
  for (std::size_t i = 0; i < order.size(); ++i) {
    sorted.positions.col(static_cast<Index>(i)) = items.positions.col(static_cast<Index>(order[i]));
    sorted.keys.push_back(items.keys[order[i]]);
    sorted.columns.push_back(items.columns[order[i]]);
  }
  Locator locator;
  locator.kind = Kind::kNearest;
  locator.box = BoxOf(sorted.positions);
  auto shared = std::make_shared<const NearestItems>(std::move(sorted));
  auto grid = std::make_shared<const SpatialGrid>(shared->positions, shared->positions);
  locator.locate = [shared, grid](const std::vector<Point3>& at, std::vector<Reply>& replies) {
    const auto n = static_cast<Index>(at.size());
    Eigen::Matrix4Xi columns = Eigen::Matrix4Xi::Zero(4, n);
    Eigen::Matrix4Xd weights = Eigen::Matrix4Xd::Zero(4, n);
    replies.resize(at.size());
    for (Index j = 0; j < n; ++j) {
      const Point3& q = at[static_cast<std::size_t>(j)];
      const Vec3 p(q[0], q[1], q[2]);
      double distance = 0;
      // The part's lowest item on a tie: its lowest key.
      const int best = grid->FindNearest(
          p, [&](int i) { return (shared->positions.col(i) - p).norm(); }, distance);
      GIPSI_CHECK(best >= 0, "a part without items was asked for the nearest");
      const auto b = static_cast<std::size_t>(best);
      columns(0, j) = static_cast<int>(shared->columns[b]);
      weights(0, j) = 1;
      replies[static_cast<std::size_t>(j)] = {distance, shared->keys[b]};
    }
    return PointMap::FromWeights(std::move(columns), std::move(weights), 0);
  };
  return std::make_unique<Interpolation>(part, std::move(locator), points, comm,
                                         std::move(part_field), nullptr);
}

std::unique_ptr<BoundaryInterpolation> MakePartsOnBoundary(
    const SimObject& part, const MeshPart& mesh_part, const Points& points, MPI_Comm comm,
    std::function<FieldId(FieldId)> part_field) {
  const BoundarySurface& boundary = part.boundary();
  auto rest = std::make_shared<Points>();
  boundary.Gather(part.domain().nodes, *rest);
  auto triangles = std::make_shared<const Triangles>(boundary.triangles);
  // The box of the faces' vertices only: a vertex that only other parts' faces touch is
  // answered for by them.
  Points used(3, 3 * triangles->cols());
  for (Index f = 0; f < triangles->cols(); ++f)
    for (Index k = 0; k < 3; ++k) used.col(3 * f + k) = rest->col((*triangles)(k, f));
  Locator locator;
  locator.kind = Kind::kTriangles;
  locator.box = BoxOf(used);
  const int rank = mesh_part.rank;
  locator.locate = [rest, triangles, rank](const std::vector<Point3>& at,
                                           std::vector<Reply>& replies) {
    const Points p = AsPoints(at);
    PointMap map = PointMap::BarycentricOnTriangles(*rest, *triangles, p);
    replies.resize(at.size());
    for (Index j = 0; j < p.cols(); ++j) {
      Vec3 reproduced = Vec3::Zero();
      for (int k = 0; k < 4; ++k)
        reproduced += map.weights()(k, j) * rest->col(map.indices()(k, j));
      replies[static_cast<std::size_t>(j)] = {(reproduced - p.col(j)).norm(), rank};
    }
    return map;
  };
  // Who owns each boundary vertex: the rank whose range of global node numbers holds its node's.
  int size = 1;
  MPI_Comm_size(comm, &size);
  std::vector<std::int64_t> first(static_cast<std::size_t>(size));
  MPI_Allgather(&mesh_part.first_owned, 1, MPI_INT64_T, first.data(), 1, MPI_INT64_T, comm);
  VertexOwners owners;
  owners.first_owned = mesh_part.first_owned;
  owners.vertex_of_owned.assign(static_cast<std::size_t>(mesh_part.num_owned), -1);
  for (std::size_t v = 0; v < boundary.vertex_to_node.size(); ++v) {
    const auto node = static_cast<std::size_t>(boundary.vertex_to_node[v]);
    const std::int64_t global = mesh_part.global[node];
    owners.global.push_back(global);
    if (static_cast<std::int64_t>(node) < mesh_part.num_owned) {
      owners.owner.push_back(-1);
      owners.vertex_of_owned[node] = static_cast<int>(v);
    } else {
      const auto after = std::upper_bound(first.begin(), first.end(), global);
      owners.owner.push_back(static_cast<int>(after - first.begin()) - 1);
    }
  }
  return std::make_unique<Interpolation>(part, std::move(locator), points, comm,
                                         std::move(part_field), nullptr, std::move(owners));
}

}  // namespace gipsi
