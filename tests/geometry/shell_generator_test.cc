#include <clocale>
#include <cmath>
#include <numbers>
#include <set>
#include <string>
#include <utility>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "gipsi/base/error.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/generators.h"
#include "gipsi/geometry/normals.h"
#include "gipsi/geometry/quality.h"

/// LeakSanitizer: libgmsh 4.8 leaks a few small allocations while meshing surfaces
/// (`meshGFace`), which `gmsh::finalize` does not free. Weak, so that another definition in the
/// test binary (or a suppressions file in LSAN_OPTIONS) takes precedence without a clash.
extern "C" __attribute__((weak, visibility("default"))) const char* __lsan_default_suppressions() {
  return "leak:libgmsh.so\n";
}

namespace gipsi {
namespace {

using ::testing::HasSubstr;
using ::testing::StrEq;
using ::testing::ThrowsMessage;

/// Volume of (x²+y²)/a² + z²/c² <= 1 below z = zb: π a² ∫_{−c}^{zb} (1 − z²/c²) dz.
double TruncatedEllipsoidVolume(double a, double c, double zb) {
  return std::numbers::pi * a * a * ((zb + c) - (zb * zb * zb + c * c * c) / (3 * c * c));
}

/// Checks what every shell must satisfy: valid, positive tets, the boundary triangles are
/// exactly the closed outward boundary of the tets, and the groups partition them.
void ExpectSoundShell(const Mesh& mesh, const std::vector<std::string>& surfaces) {
  EXPECT_NO_THROW(mesh.Validate("shell"));
  const TetQualityReport report = CheckTetQuality(mesh.nodes, mesh.tets);
  EXPECT_GT(report.min_volume, 0);
  EXPECT_TRUE(report.degenerate.empty());
  EXPECT_EQ(ExtractTetBoundary(mesh.nodes, mesh.tets).num_triangles(), mesh.num_triangles());
  std::size_t total = 0;
  for (const auto& name : surfaces) {
    const MeshGroup* group = mesh.FindGroup(name);
    ASSERT_NE(group, nullptr) << name;
    EXPECT_EQ(group->dim, 2);
    EXPECT_FALSE(group->items.empty()) << name;
    total += group->items.size();
  }
  EXPECT_EQ(total, std::size_t(mesh.num_triangles()));
  const MeshGroup* wall = mesh.FindGroup("wall");
  ASSERT_NE(wall, nullptr);
  EXPECT_EQ(wall->dim, 3);
  EXPECT_EQ(wall->items.size(), std::size_t(mesh.num_tets()));
}

/// Mean of dot(face normal, direction(centroid)) over the triangles of a group.
template <class Direction>
double MeanAlignment(const Mesh& mesh, const std::string& name, Direction&& direction) {
  const Points normals = FaceNormals(mesh.nodes, mesh.triangles);
  double sum = 0;
  const MeshGroup* group = mesh.FindGroup(name);
  for (int t : group->items) {
    const Vec3 c = (mesh.nodes.col(mesh.triangles(0, t)) + mesh.nodes.col(mesh.triangles(1, t)) +
                    mesh.nodes.col(mesh.triangles(2, t))) /
                   3;
    sum += normals.col(t).dot(direction(c));
  }
  return sum / double(group->items.size());
}

TEST(EllipsoidShell, HasPositiveTetsNamedSurfacesAndTheAnalyticVolume) {
  EllipsoidShellSpec spec;
  spec.mesh_size = 2.5;
  const Mesh mesh = MakeEllipsoidShell(spec);
  ExpectSoundShell(mesh, {"endo", "epi", "base"});
  const double analytic = TruncatedEllipsoidVolume(spec.epi_short, spec.epi_long, spec.base_z) -
                          TruncatedEllipsoidVolume(spec.endo_short, spec.endo_long, spec.base_z);
  const double volume = CheckTetQuality(mesh.nodes, mesh.tets).total_volume;
  std::cout << "[ info     ] volume / analytic = " << volume / analytic << "\n";
  EXPECT_NEAR(volume / analytic, 1, 0.03);
  for (Index n = 0; n < mesh.num_nodes(); ++n) EXPECT_LE(mesh.nodes(2, n), spec.base_z + 1e-9);
  // Outward from the wall: into the cavity on the endocardium, away from it on the
  // epicardium, up on the base.
  auto radial = [](const Vec3& c) { return c.normalized(); };
  EXPECT_LT(MeanAlignment(mesh, "endo", radial), -0.8);
  EXPECT_GT(MeanAlignment(mesh, "epi", radial), 0.8);
  EXPECT_NEAR(MeanAlignment(mesh, "base", [](const Vec3&) { return Vec3(0, 0, 1); }), 1, 1e-12);
}

/// Mean distance between consecutive columns of `points`.
double MeanStep(const Points& points) {
  double sum = 0;
  for (Index i = 1; i < points.cols(); ++i) sum += (points.col(i) - points.col(i - 1)).norm();
  return sum / double(points.cols() - 1);
}

// Gmsh numbers a volume's tets in no spatial order; read back, nodes and tets follow a Z-order
// curve, so that consecutive ones are neighbours in space (the FEM assembly colours runs of
// consecutive tets and runs them in parallel; with Gmsh's order every run touched every other).
TEST(EllipsoidShell, NumbersNodesAndTetsAlongTheDomain) {
  EllipsoidShellSpec spec;
  spec.mesh_size = 1.5;
  const Mesh mesh = MakeEllipsoidShell(spec);
  Points centroids(3, mesh.num_tets());
  for (Index e = 0; e < mesh.num_tets(); ++e) {
    centroids.col(e).setZero();
    for (int a = 0; a < 4; ++a) centroids.col(e) += 0.25 * mesh.nodes.col(mesh.tets(a, e));
  }
  const double diagonal =
      (mesh.nodes.rowwise().maxCoeff() - mesh.nodes.rowwise().minCoeff()).norm();
  std::cout << "[ info     ] " << mesh.num_tets() << " tets; mean step between consecutive tets "
            << MeanStep(centroids) / spec.mesh_size << " mesh sizes, nodes "
            << MeanStep(mesh.nodes) / spec.mesh_size << ", diagonal " << diagonal / spec.mesh_size
            << "\n";
  // Gmsh's own order measured 8.6 mesh sizes for tets and 5.8 for nodes here; along the curve
  // 0.8 and 1.6, with a few long jumps between the curve's blocks.
  EXPECT_LT(MeanStep(centroids), 2 * spec.mesh_size);
  EXPECT_LT(MeanStep(mesh.nodes), 2 * spec.mesh_size);
}

/// Distance of x from the ellipsoid (x²+y²)/a² + z²/c² = 1, to first order.
double EllipsoidGap(const Vec3& x, double a, double c) {
  const double f = (x.x() * x.x() + x.y() * x.y()) / (a * a) + x.z() * x.z() / (c * c);
  return std::abs(std::sqrt(f) - 1) * a;
}

// Order 2: the same corner mesh as order 1 (objects on linear tets see no difference), one
// middle node per tet edge, and on the endocardium the middle nodes lie on the ellipsoid where
// the straight midpoints cut inside it.
TEST(EllipsoidShell, SecondOrderPutsEdgeNodesOnTheSurfaces) {
  EllipsoidShellSpec spec;
  spec.mesh_size = 2.5;
  const Mesh linear = MakeEllipsoidShell(spec);
  spec.order = 2;
  const Mesh mesh = MakeEllipsoidShell(spec);
  EXPECT_EQ(mesh.nodes, linear.nodes);
  EXPECT_EQ(mesh.tets, linear.tets);
  EXPECT_EQ(mesh.triangles, linear.triangles);
  std::set<std::pair<int, int>> edges;
  for (Index e = 0; e < mesh.num_tets(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) edges.insert(std::minmax(mesh.tets(a, e), mesh.tets(b, e)));
  ASSERT_EQ(mesh.edge_nodes.cols(), Index(edges.size()));
  int on_endo = 0;
  double worst_node = 0, mean_midpoint = 0;
  for (Index k = 0; k < mesh.edge_nodes.cols(); ++k) {
    const Vec3 a = mesh.nodes.col(mesh.edge_node_ends(0, k));
    const Vec3 b = mesh.nodes.col(mesh.edge_node_ends(1, k));
    EXPECT_TRUE(edges.count({mesh.edge_node_ends(0, k), mesh.edge_node_ends(1, k)}));
    const double tol = 1e-6 * spec.mesh_size;
    if (EllipsoidGap(a, spec.endo_short, spec.endo_long) > tol ||
        EllipsoidGap(b, spec.endo_short, spec.endo_long) > tol ||
        (std::abs(a.z() - spec.base_z) < tol && std::abs(b.z() - spec.base_z) < tol))
      continue;
    ++on_endo;
    worst_node =
        std::max(worst_node, EllipsoidGap(mesh.edge_nodes.col(k), spec.endo_short, spec.endo_long));
    mean_midpoint += EllipsoidGap(0.5 * (a + b), spec.endo_short, spec.endo_long);
  }
  mean_midpoint /= on_endo;
  std::cout << "[ info     ] " << on_endo << " endocardial edges: middle nodes within "
            << worst_node << " of the surface, straight midpoints " << mean_midpoint
            << " inside on average\n";
  EXPECT_GT(on_endo, 50);
  EXPECT_LT(worst_node, 1e-6 * spec.mesh_size);
  EXPECT_GT(mean_midpoint, 1e-3 * spec.mesh_size);
  spec.order = 3;
  EXPECT_THAT([&] { (void)MakeEllipsoidShell(spec); },
              ThrowsMessage<InputError>(HasSubstr("order must be 1 or 2, got 3")));
}

TEST(EllipsoidShell, RejectsInconsistentDimensions) {
  EllipsoidShellSpec inside_out;
  inside_out.endo_short = 12;
  EXPECT_THAT([&] { MakeEllipsoidShell(inside_out); },
              ThrowsMessage<InputError>(
                  StrEq("ellipsoid shell: the endocardium (12 x 17) must lie inside the "
                        "epicardium (10 x 20): both semi-axes must be smaller")));
  EllipsoidShellSpec above;
  above.base_z = 18;
  EXPECT_THAT([&] { MakeEllipsoidShell(above); },
              ThrowsMessage<InputError>(
                  StrEq("ellipsoid shell: base_z 18 must cut both surfaces: expected |base_z| < "
                        "endo_long 17")));
  EllipsoidShellSpec tiny;
  tiny.mesh_size = 0.01;
  EXPECT_THAT([&] { MakeEllipsoidShell(tiny); },
              ThrowsMessage<InputError>(HasSubstr("mesh_size 0.01 is too small")));
  EllipsoidShellSpec zero;
  zero.mesh_size = 0;
  EXPECT_THAT([&] { MakeEllipsoidShell(zero); },
              ThrowsMessage<InputError>(
                  StrEq("ellipsoid shell: mesh_size must be a positive number, got 0")));
}

TEST(CylinderShell, HasPositiveTetsNamedSurfacesAndTheAnalyticVolume) {
  const double r = 1, R = 2, h = 3;
  const Mesh mesh = MakeCylinderShell(r, R, h, 0.5);
  ExpectSoundShell(mesh, {"inner", "outer", "bottom", "top"});
  const double volume = CheckTetQuality(mesh.nodes, mesh.tets).total_volume;
  const double analytic = std::numbers::pi * (R * R - r * r) * h;
  std::cout << "[ info     ] volume / analytic = " << volume / analytic << "\n";
  EXPECT_NEAR(volume / analytic, 1, 0.03);
  auto radial = [](const Vec3& c) { return Vec3(c.x(), c.y(), 0).normalized(); };
  EXPECT_LT(MeanAlignment(mesh, "inner", radial), -0.95);
  EXPECT_GT(MeanAlignment(mesh, "outer", radial), 0.95);
  EXPECT_NEAR(MeanAlignment(mesh, "top", [](const Vec3&) { return Vec3(0, 0, 1); }), 1, 1e-12);
  EXPECT_NEAR(MeanAlignment(mesh, "bottom", [](const Vec3&) { return Vec3(0, 0, -1); }), 1, 1e-12);
}

// Order 2: the same corners; the middle node of every edge with both ends on the outer
// cylinder lies on it (the straight midpoint cuts inside unless the edge runs along z).
TEST(CylinderShell, SecondOrderPutsEdgeNodesOnTheCylinders) {
  const double r = 1, R = 2, h = 3;
  const Mesh linear = MakeCylinderShell(r, R, h, 0.5);
  const Mesh mesh = MakeCylinderShell(r, R, h, 0.5, 2);
  EXPECT_EQ(mesh.nodes, linear.nodes);
  EXPECT_EQ(mesh.tets, linear.tets);
  int on_outer = 0;
  for (Index k = 0; k < mesh.edge_nodes.cols(); ++k) {
    const Vec3 a = mesh.nodes.col(mesh.edge_node_ends(0, k));
    const Vec3 b = mesh.nodes.col(mesh.edge_node_ends(1, k));
    if (std::abs(a.head<2>().norm() - R) > 1e-9 || std::abs(b.head<2>().norm() - R) > 1e-9)
      continue;
    ++on_outer;
    EXPECT_NEAR(mesh.edge_nodes.col(k).head<2>().norm(), R, 1e-9) << "edge " << k;
  }
  EXPECT_GT(on_outer, 100);
}

TEST(CylinderShell, IsDeterministic) {
  const Mesh a = MakeCylinderShell(1, 2, 1, 0.6);
  const Mesh b = MakeCylinderShell(1, 2, 1, 0.6);
  EXPECT_EQ(a.nodes, b.nodes);
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.triangles, b.triangles);
}

TEST(CylinderShell, LeavesTheProcessLocaleUnchanged) {
  const std::string before = std::setlocale(LC_ALL, nullptr);
  MakeCylinderShell(1, 2, 1, 0.8);
  EXPECT_EQ(std::setlocale(LC_ALL, nullptr), before);
}

// gmsh::initialize sets the calling thread's OpenMP team size to one and gmsh::finalize leaves it
// there: every scene that generated a mesh then ran GiPSi's parallel loops on one thread.
TEST(CylinderShell, LeavesTheOpenMpTeamSizeUnchanged) {
#ifdef _OPENMP
  const int before = omp_get_max_threads();
  omp_set_num_threads(3);  // not Gmsh's 1, whatever the machine
  MakeCylinderShell(1, 2, 1, 0.8);
  const int after = omp_get_max_threads();
  omp_set_num_threads(before);
  EXPECT_EQ(after, 3);
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

TEST(CylinderShell, RejectsInnerRadiusNotBelowOuter) {
  EXPECT_THAT([] { MakeCylinderShell(2, 2, 1, 0.5); },
              ThrowsMessage<InputError>(
                  StrEq("cylinder shell: inner_radius 2 must be smaller than outer_radius 2")));
  EXPECT_THAT(
      [] { MakeCylinderShell(1, 2, -1, 0.5); },
      ThrowsMessage<InputError>(StrEq("cylinder shell: height must be a positive number, got -1")));
}

}  // namespace
}  // namespace gipsi
