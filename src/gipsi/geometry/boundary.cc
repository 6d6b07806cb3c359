#include "gipsi/geometry/boundary.h"

#include <algorithm>
#include <array>

#include "gipsi/base/error.h"
#include "gipsi/geometry/quality.h"

namespace gipsi {
namespace {

/// Faces of a positively oriented tet (0,1,2,3), each oriented so that its right-hand normal
/// points away from the opposite node: face f is opposite node f.
constexpr std::array<std::array<int, 3>, 4> kOutwardFaces = {
    {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};

struct FaceKey {
  std::array<int, 3> sorted;  ///< node indices, increasing
  int tet;
  int face;  ///< local face (opposite local node)
};

/// Renumbers `triangles` (domain nodes) to boundary vertices: the used nodes in increasing
/// order become vertices 0..V-1.
BoundarySurface Renumber(const Triangles& triangles, Index num_nodes) {
  BoundarySurface surface;
  std::vector<int> vertex_of_node(std::size_t(num_nodes), -1);
  for (Index t = 0; t < triangles.cols(); ++t)
    for (int a = 0; a < 3; ++a) vertex_of_node[std::size_t(triangles(a, t))] = 0;
  for (std::size_t n = 0; n < vertex_of_node.size(); ++n) {
    if (vertex_of_node[n] == 0) {
      vertex_of_node[n] = int(surface.vertex_to_node.size());
      surface.vertex_to_node.push_back(int(n));
    }
  }
  surface.triangles.resize(3, triangles.cols());
  for (Index t = 0; t < triangles.cols(); ++t)
    for (int a = 0; a < 3; ++a)
      surface.triangles(a, t) = vertex_of_node[std::size_t(triangles(a, t))];
  return surface;
}

}  // namespace

void BoundarySurface::Gather(const Points& domain_positions, Points& out) const {
  out.resize(3, num_vertices());
  for (Index v = 0; v < num_vertices(); ++v) {
    const int n = vertex_to_node[std::size_t(v)];
    GIPSI_DCHECK(n < domain_positions.cols());
    out.col(v) = domain_positions.col(n);
  }
}

BoundarySurface ExtractTetBoundary(const Points& nodes, const Tets& tets) {
  // Collect every face under its sorted node triple; faces seen once are on the boundary.
  std::vector<FaceKey> faces;
  faces.reserve(std::size_t(tets.cols()) * 4);
  for (Index e = 0; e < tets.cols(); ++e) {
    for (int f = 0; f < 4; ++f) {
      FaceKey key{{}, int(e), f};
      for (int a = 0; a < 3; ++a) key.sorted[std::size_t(a)] = tets(kOutwardFaces[f][a], e);
      std::sort(key.sorted.begin(), key.sorted.end());
      faces.push_back(key);
    }
  }
  std::sort(faces.begin(), faces.end(), [](const FaceKey& x, const FaceKey& y) {
    return x.sorted != y.sorted ? x.sorted < y.sorted
                                : (x.tet != y.tet ? x.tet < y.tet : x.face < y.face);
  });
  std::vector<std::pair<int, int>> boundary;  // (tet, local face), in tet order below
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].sorted == faces[i].sorted) ++j;
    if (j == i + 1) boundary.emplace_back(faces[i].tet, faces[i].face);
    i = j;
  }
  std::sort(boundary.begin(), boundary.end());

  Triangles triangles(3, Index(boundary.size()));
  std::vector<int> face_to_tet(boundary.size());
  for (std::size_t b = 0; b < boundary.size(); ++b) {
    const auto [e, f] = boundary[b];
    const auto tet = tets.col(e);
    // Reverse the faces of a negatively oriented tet (node order 0-1-2-3).
    const bool negative = TetSignedVolume(nodes.col(tet[0]), nodes.col(tet[1]), nodes.col(tet[2]),
                                          nodes.col(tet[3])) < 0;
    const auto& local = kOutwardFaces[std::size_t(f)];
    triangles(0, Index(b)) = tet[local[0]];
    triangles(1, Index(b)) = tet[negative ? local[2] : local[1]];
    triangles(2, Index(b)) = tet[negative ? local[1] : local[2]];
    face_to_tet[b] = e;
  }
  BoundarySurface surface = Renumber(triangles, nodes.cols());
  surface.face_to_tet = std::move(face_to_tet);
  return surface;
}

BoundarySurface MakeBoundary(const Mesh& mesh) {
  if (mesh.num_tets() > 0) return ExtractTetBoundary(mesh.nodes, mesh.tets);
  if (mesh.num_triangles() > 0) {
    BoundarySurface surface = Renumber(mesh.triangles, mesh.num_nodes());
    surface.face_to_tet.assign(std::size_t(mesh.num_triangles()), -1);
    return surface;
  }
  ThrowInputError("", "mesh",
                  fmt::format("has neither tetrahedra nor triangles ({} nodes); a boundary "
                              "surface needs one of them",
                              mesh.num_nodes()));
}

}  // namespace gipsi
