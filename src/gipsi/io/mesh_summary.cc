#include "gipsi/io/mesh_summary.h"

#include <map>
#include <utility>

#include <fmt/format.h>

#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/edge_key.h"
#include "gipsi/geometry/quality.h"

namespace gipsi {

std::string DescribeMesh(const Mesh& mesh) {
  std::string out;
  out += fmt::format("nodes:           {}\n", mesh.num_nodes());
  out += fmt::format("tetrahedra:      {}\n", mesh.num_tets());
  out += fmt::format("triangles:       {}\n", mesh.num_triangles());
  if (mesh.edge_nodes.cols() > 0) {
    Index curved = 0;
    for (Index k = 0; k < mesh.edge_nodes.cols(); ++k)
      curved += IsOffMidpoint(mesh.nodes.col(mesh.edge_node_ends(0, k)),
                              mesh.nodes.col(mesh.edge_node_ends(1, k)), mesh.edge_nodes.col(k));
    out += fmt::format(
        "second order:    {} edge nodes, {} off their edge's midpoint (curved; "
        "used by MixedSolid)\n",
        mesh.edge_nodes.cols(), curved);
  }
  if (mesh.num_nodes() > 0) {
    Vec3 lo = mesh.nodes.rowwise().minCoeff(), hi = mesh.nodes.rowwise().maxCoeff();
    out += fmt::format("bounding box:    [{:.6g}, {:.6g}, {:.6g}] to [{:.6g}, {:.6g}, {:.6g}]\n",
                       lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z());
    out += fmt::format("size:            {:.6g} x {:.6g} x {:.6g}\n", hi.x() - lo.x(),
                       hi.y() - lo.y(), hi.z() - lo.z());
  }
  if (mesh.num_tets() > 0 || mesh.num_triangles() > 0) {
    BoundarySurface boundary = MakeBoundary(mesh);
    out += fmt::format("boundary:        {} triangles on {} vertices\n", boundary.num_triangles(),
                       boundary.num_vertices());
    // Edge use counts tell whether the boundary is closed and manifold.
    std::map<std::pair<int, int>, int> edges;
    for (Index t = 0; t < boundary.num_triangles(); ++t)
      for (int a = 0; a < 3; ++a) {
        int i = boundary.triangles(a, t), j = boundary.triangles((a + 1) % 3, t);
        ++edges[{std::min(i, j), std::max(i, j)}];
      }
    std::size_t open = 0, non_manifold = 0;
    for (const auto& [e, n] : edges) {
      open += n == 1;
      non_manifold += n > 2;
    }
    out += fmt::format("surface:         {} ({} open edges, {} non-manifold edges)\n",
                       open == 0 && non_manifold == 0 ? "closed and manifold" : "not closed", open,
                       non_manifold);
  }
  if (!mesh.groups.empty()) {
    out += "named groups:\n";
    for (const auto& g : mesh.groups) {
      const char* kind = g.dim == 0 ? "nodes" : g.dim == 2 ? "triangles" : "tetrahedra";
      out += fmt::format("  {:<20} {} {}\n", g.name, g.items.size(), kind);
    }
  }
  if (mesh.num_tets() > 0) {
    TetQualityReport q = CheckTetQuality(mesh.nodes, mesh.tets);
    out += "quality:\n";
    out += fmt::format("  volume:         {:.6g} (element min {:.4g}, max {:.4g})\n",
                       q.total_volume, q.min_volume, q.max_volume);
    out += fmt::format("  aspect ratio:   min {:.4g}, mean {:.4g}, max {:.4g} (tet {})\n",
                       q.min_aspect, q.mean_aspect, q.max_aspect,
                       q.worst_aspect_tet < 0 ? std::string("-")
                                              : fmt::format("{}", mesh.TetId(q.worst_aspect_tet)));
    out += fmt::format("  inverted tets:  {}{}\n", q.inverted.size(),
                       q.inverted.empty() ? "" : " — ids: " + mesh.TetIdList(q.inverted));
    out += fmt::format("  degenerate:     {}{}\n", q.degenerate.size(),
                       q.degenerate.empty() ? "" : " — ids: " + mesh.TetIdList(q.degenerate));
  }
  return out;
}

}  // namespace gipsi
