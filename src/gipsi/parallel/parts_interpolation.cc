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

#include "gipsi/base/error.h"
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

class Interpolation final : public PartsInterpolation {
 public:
  Interpolation(const SimObject& part, const MeshPart& mesh_part, const Points& points,
                MPI_Comm comm, std::function<FieldId(FieldId)> part_field,
                std::function<void(Eigen::Ref<Eigen::MatrixXd>)> share);

  [[nodiscard]] Index num_points() const override { return num_points_; }
  [[nodiscard]] double max_distance() const override { return max_distance_; }
  void Interpolate(FieldId id, Eigen::Ref<Eigen::MatrixXd> out,
                   std::optional<double> no_data) const override;

 private:
  // The nearest part found so far for each of this rank's points: its rank, and where the point
  // was in what that rank was sent (the round, the position among the points sent to it then).
  struct Nearest {
    double distance = std::numeric_limits<double>::infinity();
    int rank = std::numeric_limits<int>::max();
    Choice choice;
  };
  // What a rank located for the others in one round: the points' weights on its part, in the
  // order they came, and where each sender's points begin.
  struct Located {
    PointMap map;
    std::vector<int> begin;
  };
  // Sends `to[r]` (points `index[r]` of this rank's) to rank r, which locates them on its part
  // and answers their distances; keeps each point's nearest part. Returns what this rank
  // located for the others. Collective.
  Located Ask(int round, const std::vector<std::vector<Point3>>& to,
              const std::vector<std::vector<Index>>& index, std::vector<Nearest>& nearest) const;

  const SimObject& part_;
  const MeshPart& mesh_part_;
  MPI_Comm comm_;
  std::function<FieldId(FieldId)> part_field_;
  std::function<void(Eigen::Ref<Eigen::MatrixXd>)> share_;
  Index num_points_ = 0;
  double max_distance_ = 0;
  // The points other ranks asked of this part (in rank order), and how many each rank asked.
  PointMap answer_;
  std::vector<int> answer_counts_;
  // The points this rank asked of each rank (in rank order: the point each arriving value is
  // for), and how many.
  std::vector<Index> asked_;
  std::vector<int> asked_counts_;
  // Buffers of Interpolate.
  mutable Eigen::MatrixXd source_, answers_, received_;
  mutable std::vector<int> send_counts_, send_offsets_, receive_counts_, receive_offsets_;
};

Interpolation::Interpolation(const SimObject& part, const MeshPart& mesh_part, const Points& points,
                             MPI_Comm comm, std::function<FieldId(FieldId)> part_field,
                             std::function<void(Eigen::Ref<Eigen::MatrixXd>)> share)
    : part_(part),
      mesh_part_(mesh_part),
      comm_(comm),
      part_field_(std::move(part_field)),
      share_(std::move(share)),
      num_points_(points.cols()) {
  const int size = mesh_part.size;
  const auto ranks = static_cast<std::size_t>(size);
  int bad = points.allFinite() ? 0 : 1;
  MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT, MPI_MAX, comm);
  if (bad != 0) throw InputError("a point to interpolate the split object at is not finite");
  const Mesh& mesh = *mesh_part.mesh;
  GIPSI_CHECK(mesh.num_nodes() > 0, "a part without nodes");

  // Every part's bounding box, and a slack of 1e-9 of the whole domain's diagonal for points
  // that lie on a box's side up to rounding.
  Box mine;
  for (int k = 0; k < 3; ++k) {
    mine.lo[static_cast<std::size_t>(k)] = mesh.nodes.row(k).minCoeff();
    mine.hi[static_cast<std::size_t>(k)] = mesh.nodes.row(k).maxCoeff();
  }
  std::vector<Box> boxes(ranks);
  MPI_Allgather(&mine, 6, MPI_DOUBLE, boxes.data(), 6, MPI_DOUBLE, comm);
  Box all = boxes.front();
  for (const Box& box : boxes)
    for (std::size_t k = 0; k < 3; ++k) {
      all.lo[k] = std::min(all.lo[k], box.lo[k]);
      all.hi[k] = std::max(all.hi[k], box.hi[k]);
    }
  const double slack =
      1e-9 * std::hypot(all.hi[0] - all.lo[0], all.hi[1] - all.lo[1], all.hi[2] - all.lo[2]);

  auto point = [&points](Index j) { return Point3{points(0, j), points(1, j), points(2, j)}; };
  std::vector<Nearest> nearest(static_cast<std::size_t>(num_points_));
  // First the parts whose boxes hold the point; then, for a point no part holds, every other
  // part whose box is no farther than the nearest part found (which may then be nearer).
  std::array<Located, 2> located;
  for (const int round : {0, 1}) {
    std::vector<std::vector<Point3>> to(ranks);
    std::vector<std::vector<Index>> index(ranks);
    for (Index j = 0; j < num_points_; ++j) {
      const Nearest& found = nearest[static_cast<std::size_t>(j)];
      if (round == 1 && found.distance <= slack) continue;
      const Point3 p = point(j);
      for (int r = 0; r < size; ++r) {
        const double d = BoxDistance(boxes[static_cast<std::size_t>(r)], p);
        const bool ask = round == 1 ? d > slack && d <= found.distance : d <= slack;
        if (!ask) continue;
        to[static_cast<std::size_t>(r)].push_back(p);
        index[static_cast<std::size_t>(r)].push_back(j);
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
  std::vector<double> distance;
  Located located{Locate(*mesh_part_.mesh, got.items, distance), {}};
  std::vector<std::vector<double>> reply(to.size());
  std::size_t k = 0;
  for (std::size_t r = 0; r < to.size(); ++r) {
    located.begin.push_back(static_cast<int>(k));
    for (int c = 0; c < got.counts[r]; ++c) reply[r].push_back(distance[k++]);
  }
  const detail::Received<double> back = detail::Exchange(reply, comm_);
  k = 0;
  for (std::size_t r = 0; r < to.size(); ++r) {
    GIPSI_CHECK(back.counts[r] == static_cast<int>(index[r].size()), "answers lost");
    for (std::size_t position = 0; position < index[r].size(); ++position) {
      Nearest& found = nearest[static_cast<std::size_t>(index[r][position])];
      const double d = back.items[k++];
      const int rank = static_cast<int>(r);
      if (d < found.distance || (d == found.distance && rank < found.rank))
        found = {d, rank, {round, static_cast<int>(position)}};
    }
  }
  return located;
}

void Interpolation::Interpolate(FieldId id, Eigen::Ref<Eigen::MatrixXd> out,
                                std::optional<double> no_data) const {
  const FieldId field = part_field_(id);
  const FieldInfo& info = part_.field_info(field);
  GIPSI_CHECK(info.location == FieldLocation::kNode, "field '{}' is not a node field", info.name);
  const Index components = info.components;
  GIPSI_CHECK(out.rows() == components && out.cols() == num_points_,
              "interpolation into {}×{} values, expected {}×{}", out.rows(), out.cols(), components,
              num_points_);
  source_.resize(components, part_.FieldCount(field));
  part_.ReadField(field, source_);
  share_(source_);
  answers_.resize(components, answer_.num_targets());
  if (no_data) {
    answer_.ApplyMarked(source_, answers_, *no_data);
  } else {
    answer_.Apply(source_, answers_);
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

}  // namespace

std::unique_ptr<PartsInterpolation> MakePartsInterpolation(
    const SimObject& part, const MeshPart& mesh_part, const Points& points, MPI_Comm comm,
    std::function<FieldId(FieldId)> part_field,
    std::function<void(Eigen::Ref<Eigen::MatrixXd>)> share) {
  return std::make_unique<Interpolation>(part, mesh_part, points, comm, std::move(part_field),
                                         std::move(share));
}

}  // namespace gipsi
