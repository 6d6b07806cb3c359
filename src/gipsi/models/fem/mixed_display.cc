// MixedSolid's display geometry — its curved boundary drawn from the quadratic mesh, and any
// embedded display surface following the P2 solution rather than the vertices alone — and
// the same quadratic interpolation for probes at points.

#include <cstdint>
#include <unordered_map>

#include <Eigen/LU>

#include "gipsi/models/fem/mixed_solid.h"

namespace gipsi {
namespace {

/// Calls fn(edge node, w) for each edge between two nodes that target j's weights blend, with
/// w = 4 w_a w_b: the P2 interpolation is the linear blend Σ w_a f_a plus Σ w (f_ab − (f_a +
/// f_b)/2) over those edges (N_a = L_a (2 L_a − 1), N_ab = 4 L_a L_b), exact for a target
/// inside a tet or on a face.
template <typename Fn>
void ForEachBow(const QuadraticTets& mesh, const Eigen::Matrix4Xi& nodes,
                const Eigen::Matrix4Xd& weights, Index j, Fn&& fn) {
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) {
      const double w = 4 * weights(a, j) * weights(b, j);
      if (w == 0) continue;
      const int node = mesh.EdgeNode(nodes(a, j), nodes(b, j));
      if (node >= 0) fn(node, w);
    }
}

}  // namespace

void MixedSolid::MakeCurvedDisplay() {
  // Display vertices: the boundary vertices (in the boundary's numbering), then the edge nodes
  // of the boundary faces. Each 6-node face (vertices 0..2, edge nodes 3 = (0,1), 4 = (1,2),
  // 5 = (0,2)) becomes four triangles of its orientation.
  const BoundarySurface& bnd = boundary();
  const Index nb = bnd.num_vertices();
  std::unordered_map<int, int> display_of_edge;  // P2 edge node → display vertex
  std::vector<int> edge_nodes;
  Triangles triangles(3, 4 * bnd.num_triangles());
  for (Index f = 0; f < bnd.num_triangles(); ++f) {
    int d[6];
    for (int i = 0; i < 3; ++i) d[i] = bnd.triangles(i, f);
    for (int k = 0; k < 3; ++k) {
      const int node = faces_(3 + k, f);
      const auto [it, added] =
          display_of_edge.emplace(node, static_cast<int>(nb) + static_cast<int>(edge_nodes.size()));
      if (added) edge_nodes.push_back(node);
      d[3 + k] = it->second;
    }
    triangles.col(4 * f) << d[0], d[3], d[5];
    triangles.col(4 * f + 1) << d[3], d[1], d[4];
    triangles.col(4 * f + 2) << d[5], d[4], d[2];
    triangles.col(4 * f + 3) << d[3], d[4], d[5];
  }
  // The map: a boundary vertex is its node; an edge node is the mean of its ends, to which
  // CorrectDisplayPositions adds the edge's bow.
  const Index n = nb + static_cast<Index>(edge_nodes.size());
  Eigen::Matrix4Xi indices = Eigen::Matrix4Xi::Zero(4, n);
  Eigen::Matrix4Xd weights = Eigen::Matrix4Xd::Zero(4, n);
  Points rest(3, n);
  for (Index j = 0; j < nb; ++j) {
    indices(0, j) = bnd.vertex_to_node[static_cast<std::size_t>(j)];
    weights(0, j) = 1;
    rest.col(j) = mesh_.rest.col(indices(0, j));
  }
  for (std::size_t k = 0; k < edge_nodes.size(); ++k) {
    const Index j = nb + static_cast<Index>(k);
    const Index edge = edge_nodes[k] - mesh_.num_vertices;
    indices.col(j).head<2>() = mesh_.edges.col(edge);
    weights.col(j).head<2>().setConstant(0.5);
    rest.col(j) = mesh_.rest.col(edge_nodes[k]);
  }
  SetDisplayGeometry(std::move(triangles),
                     PointMap::FromWeights(std::move(indices), std::move(weights), 0),
                     std::move(rest));
}

void MixedSolid::OnDisplayChanged() {
  // For every display vertex, the edges whose bows its P2 position adds (ForEachBow).
  display_bow_start_.assign(1, 0);
  display_bow_node_.clear();
  display_bow_weight_.clear();
  const PointMap& map = *display().map;
  for (Index j = 0; j < map.num_targets(); ++j) {
    ForEachBow(mesh_, map.indices(), map.weights(), j, [&](int node, double w) {
      display_bow_node_.push_back(node);
      display_bow_weight_.push_back(w);
    });
    display_bow_start_.push_back(static_cast<int>(display_bow_node_.size()));
  }
}

void MixedSolid::CorrectDisplayPositions(DisplayGeometry& display) const {
  if (static_cast<Index>(display_bow_start_.size()) != display.positions.cols() + 1) return;
  const Index nv = mesh_.num_vertices;
  for (Index j = 0; j < display.positions.cols(); ++j)
    for (int k = display_bow_start_[static_cast<std::size_t>(j)];
         k < display_bow_start_[static_cast<std::size_t>(j) + 1]; ++k) {
      const int node = display_bow_node_[static_cast<std::size_t>(k)];
      const Index edge = node - nv;
      const Vec3 x = mesh_.rest.col(node) + state_.z.segment<3>(3 * node);
      const Vec3 mid = 0.5 * (vertex_positions_.col(mesh_.edges(0, edge)) +
                              vertex_positions_.col(mesh_.edges(1, edge)));
      display.positions.col(j) += display_bow_weight_[static_cast<std::size_t>(k)] * (x - mid);
    }
}

PointMap MixedSolid::MapFromNodes(const Points& targets) const {
  PointMap straight = SimObject::MapFromNodes(targets);
  if (mesh_.num_curved_edges == 0 || targets.cols() == 0) return straight;
  // The straight map names its tet by the tet's four vertices in the domain's order, which is
  // the quadratic element's (ElevateToQuadratic keeps both).
  const Tets& tets = domain().tets;
  auto key = [](const auto& v) {
    std::uint64_t h = 0;
    for (int k = 0; k < 4; ++k) h = h * 1000003ULL + static_cast<std::uint64_t>(v[k]);
    return h;
  };
  std::unordered_multimap<std::uint64_t, Index> tet_of;
  tet_of.reserve(static_cast<std::size_t>(tets.cols()));
  for (Index e = 0; e < tets.cols(); ++e)
    if (mesh_.IsCurved(e)) tet_of.emplace(key(tets.col(e)), e);
  Eigen::Matrix4Xd weights = straight.weights();
  const Points& x0 = mesh_.rest;
  const Points& corners = domain().nodes;
  double max_distance = 0;
  for (Index j = 0; j < targets.cols(); ++j) {
    const auto column = straight.indices().col(j);
    // How far the straight weights leave the target: zero inside the straight mesh, the
    // clamping's offset outside it (where a curved boundary may still hold the target).
    Vec3 straight_point = Vec3::Zero();
    for (int k = 0; k < 4; ++k) straight_point += weights(k, j) * corners.col(column[k]);
    const double straight_distance = (straight_point - targets.col(j)).norm();
    Index e = -1;
    const auto [first, last] = tet_of.equal_range(key(column));
    for (auto it = first; it != last && e < 0; ++it)
      if (tets.col(it->second) == column) e = it->second;
    if (e < 0) {  // a straight tet: its barycentrics are the map's own
      max_distance = std::max(max_distance, straight_distance);
      continue;
    }
    Eigen::Matrix<double, 3, 10> x;
    for (int a = 0; a < 10; ++a) x.col(a) = x0.col(mesh_.elements(a, e));
    const double size =
        (x.col(1) - x.col(0)).norm() + (x.col(2) - x.col(0)).norm() + (x.col(3) - x.col(0)).norm();
    Eigen::Vector4d l = weights.col(j);
    bool converged = false;
    for (int it = 0; it < 30 && !converged; ++it) {
      const Vec3 r = x * QuadraticTetShape(l) - targets.col(j);
      if (r.norm() <= 1e-14 * size) {
        converged = true;
        break;
      }
      const Eigen::Matrix<double, 10, 4> d = QuadraticTetShapeDerivatives(l);
      Mat3 jacobian;  // ∂x/∂ξ_k with ξ = (L_1, L_2, L_3), L_0 = 1 − Σ ξ
      for (int k = 0; k < 3; ++k) jacobian.col(k) = x * (d.col(k + 1) - d.col(0));
      const Vec3 step = jacobian.partialPivLu().solve(r);
      if (!step.allFinite()) break;
      l.tail<3>() -= step;
      l[0] = 1 - l.tail<3>().sum();
    }
    // Inside the straight mesh the curved tet's map holds the target (or, beside a curved face,
    // its neighbour's, whose polynomial continues smoothly there); outside it, only a solution
    // inside this curved tet is the target's, else the clamped straight weights stay.
    const bool inside_straight = straight_distance <= 1e-12 * size;
    if (converged && (inside_straight || l.minCoeff() >= -1e-9)) {
      weights.col(j) = l;
      max_distance = std::max(max_distance, (x * QuadraticTetShape(l) - targets.col(j)).norm());
    } else {
      max_distance = std::max(max_distance, straight_distance);
    }
  }
  return PointMap::FromWeights(straight.indices(), std::move(weights), max_distance);
}

void MixedSolid::CorrectInterpolated(FieldId id, const Eigen::Matrix4Xi& nodes,
                                     const Eigen::Matrix4Xd& weights,
                                     Eigen::Ref<Eigen::MatrixXd> at) const {
  const bool velocity = id == mech_.velocity;
  if (id != mech_.displacement && id != mech_.position && !(velocity && dynamic())) return;
  // The field at P2 node n: displacement and position differ by the rest position, whose bow
  // (a curved edge's) the position keeps and the displacement does not.
  const auto value = [&](Index n) -> Vec3 {
    if (velocity) return state_.scheme.v().segment<3>(3 * n);
    const Vec3 u = state_.z.segment<3>(3 * n);
    return id == mech_.position ? Vec3(mesh_.rest.col(n) + u) : u;
  };
  const Index nv = mesh_.num_vertices;
  for (Index j = 0; j < at.cols(); ++j)
    ForEachBow(mesh_, nodes, weights, j, [&](int node, double w) {
      const Index edge = node - nv;
      at.col(j) +=
          w * (value(node) - 0.5 * (value(mesh_.edges(0, edge)) + value(mesh_.edges(1, edge))));
    });
}

}  // namespace gipsi
