#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/quality.h"
#include "gipsi/io/mesh_io.h"
#include "test_paths.h"

namespace gipsi {
namespace {

double TetVolume(const Mesh& mesh) {
  double volume = 0;
  for (Index e = 0; e < mesh.num_tets(); ++e) {
    const double v =
        TetSignedVolume(mesh.nodes.col(mesh.tets(0, e)), mesh.nodes.col(mesh.tets(1, e)),
                        mesh.nodes.col(mesh.tets(2, e)), mesh.nodes.col(mesh.tets(3, e)));
    EXPECT_GT(v, 0) << "tet " << e;
    volume += v;
  }
  return volume;
}

TEST(TetsInSurface, FillsABoxSurfaceExactly) {
  // The boundary of a coarse tet box is a closed surface with flat faces and sharp edges, which
  // the crease angle keeps: the filled volume is the box's to round-off.
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(2, 1, 1), {2, 1, 1});
  const BoundarySurface b = ExtractTetBoundary(box.nodes, box.tets);
  Points vertices(3, b.num_vertices());
  for (Index v = 0; v < b.num_vertices(); ++v)
    vertices.col(v) = box.nodes.col(b.vertex_to_node[static_cast<std::size_t>(v)]);
  const Mesh filled = MakeTetsInSurface(vertices, b.triangles, 0.25);
  EXPECT_GT(filled.num_tets(), 100);
  EXPECT_NEAR(TetVolume(filled), 2.0, 1e-9);
}

TEST(TetsInSurface, FillsTheLiverSurface) {
  // SOFA's coarse liver surface (cm): a closed 2-manifold Gmsh remeshes and fills.
  const Mesh surface = ReadMesh(std::string(GIPSI_SHARED_DATA_DIR) + "/liver/liver.obj");
  const Mesh liver = MakeTetsInSurface(surface.nodes, surface.triangles, 0.5);
  EXPECT_GT(liver.num_tets(), 1000);
  // The filled volume matches the surface's enclosed volume to the remeshing error (~1 %).
  double enclosed = 0;
  for (Index t = 0; t < surface.num_triangles(); ++t)
    enclosed += surface.nodes.col(surface.triangles(0, t))
                    .dot(surface.nodes.col(surface.triangles(1, t))
                             .cross(surface.nodes.col(surface.triangles(2, t)))) /
                6.0;
  EXPECT_NEAR(TetVolume(liver) / std::abs(enclosed), 1.0, 0.02);
}

TEST(TetsInSurface, RejectsAnOpenSurface) {
  const Mesh box = MakeTetBox(Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1});
  const BoundarySurface b = ExtractTetBoundary(box.nodes, box.tets);
  Points vertices(3, b.num_vertices());
  for (Index v = 0; v < b.num_vertices(); ++v)
    vertices.col(v) = box.nodes.col(b.vertex_to_node[static_cast<std::size_t>(v)]);
  std::vector<Index> keep;
  for (Index t = 0; t < b.num_triangles(); ++t)
    if (vertices(2, b.triangles(0, t)) + vertices(2, b.triangles(1, t)) +
            vertices(2, b.triangles(2, t)) <
        3)
      keep.push_back(t);  // drop the top face: an open box
  Triangles open(3, static_cast<Index>(keep.size()));
  for (std::size_t k = 0; k < keep.size(); ++k)
    open.col(static_cast<Index>(k)) = b.triangles.col(keep[k]);
  EXPECT_THROW(MakeTetsInSurface(vertices, open, 0.25), InputError);
}

}  // namespace
}  // namespace gipsi
