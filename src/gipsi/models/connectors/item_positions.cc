#include "gipsi/models/connectors/item_positions.h"

namespace gipsi {

Points ItemRestPositions(const SimObject& object, FieldLocation location) {
  const Mesh& mesh = object.domain();
  const BoundarySurface& bnd = object.boundary();
  switch (location) {
    case FieldLocation::kNode:
      return mesh.nodes;
    case FieldLocation::kElement: {
      const bool tets = mesh.num_tets() > 0;
      Points out(3, NumDomainElements(mesh));
      for (Index e = 0; e < out.cols(); ++e) {
        Vec3 c = Vec3::Zero();
        const int k = tets ? 4 : 3;
        for (int a = 0; a < k; ++a)
          c += mesh.nodes.col(tets ? mesh.tets(a, e) : mesh.triangles(a, e));
        out.col(e) = c / k;
      }
      return out;
    }
    case FieldLocation::kBoundaryVertex: {
      Points out;
      bnd.Gather(mesh.nodes, out);
      return out;
    }
    case FieldLocation::kBoundaryFace: {
      Points out(3, bnd.num_triangles());
      for (Index t = 0; t < out.cols(); ++t) {
        Vec3 c = Vec3::Zero();
        for (int a = 0; a < 3; ++a)
          c += mesh.nodes.col(bnd.vertex_to_node[static_cast<std::size_t>(bnd.triangles(a, t))]);
        out.col(t) = c / 3.0;
      }
      return out;
    }
    case FieldLocation::kGlobal:
      return Points(3, 0);
  }
  return Points(3, 0);
}

}  // namespace gipsi
