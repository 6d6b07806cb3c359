/// @file
/// A whole mesh sliced into one rank's block.

#include "gipsi/geometry/mesh_block.h"

#include "gipsi/base/error.h"

namespace gipsi {

MeshBlock BlockOfMesh(const Mesh& whole, int rank, int size) {
  GIPSI_CHECK(size >= 1 && rank >= 0 && rank < size);
  MeshBlock block;
  block.rank = rank;
  block.size = size;
  block.num_nodes = whole.num_nodes();
  block.num_tets = whole.num_tets();
  block.num_triangles = whole.num_triangles();
  const Index n0 = block.node_begin(), n1 = BlockBegin(block.num_nodes, rank + 1, size);
  const Index e0 = block.tet_begin(), e1 = BlockBegin(block.num_tets, rank + 1, size);
  const Index t0 = BlockBegin(block.num_triangles, rank, size);
  const Index t1 = BlockBegin(block.num_triangles, rank + 1, size);
  block.first_triangle = t0;
  block.nodes = whole.nodes.middleCols(n0, n1 - n0);
  block.tets = whole.tets.middleCols(e0, e1 - e0);
  block.triangles = whole.triangles.middleCols(t0, t1 - t0);
  if (!whole.tet_ids.empty()) {
    block.tet_ids.assign(whole.tet_ids.begin() + e0, whole.tet_ids.begin() + e1);
    block.tet_id_kind = whole.tet_id_kind;
  }
  for (const MeshGroup& group : whole.groups) {
    MeshGroup g{group.name, group.dim, {}};
    const Index begin = group.dim == 0 ? n0 : group.dim == 2 ? t0 : e0;
    const Index end = group.dim == 0 ? n1 : group.dim == 2 ? t1 : e1;
    for (int item : group.items)
      if (item >= begin && item < end) g.items.push_back(item);
    block.groups.push_back(std::move(g));
  }
  return block;
}

}  // namespace gipsi
