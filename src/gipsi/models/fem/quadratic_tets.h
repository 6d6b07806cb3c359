#pragma once
/// @file
/// Quadratic (P2, 10-node) tetrahedra and 6-node triangles: a linear tet mesh elevated to P2
/// by adding one node on every edge — at its midpoint (straight-sided elements: the map from
/// the reference element is affine and shape-function gradients are those of P1 combined), or
/// where a second-order mesh file puts it (curved, isoparametric elements) — the shape
/// functions, and the quadrature rules the mixed elements use.
///
/// Shape functions in barycentric coordinates L_0..L_3 (Σ L = 1, ∇L_k the constant P1
/// gradients): vertex a: N_a = L_a (2 L_a − 1); midpoint of edge (i, j): N = 4 L_i L_j.
/// Local node order (VTK_QUADRATIC_TETRA, so VTU files need no reordering): the four vertices,
/// then the midpoints of edges (0,1), (1,2), (0,2), (0,3), (1,3), (2,3). Triangles (6 nodes,
/// VTK_QUADRATIC_TRIANGLE): the three vertices, then the midpoints of (0,1), (1,2), (0,2).
///
/// Quadrature (weights sum to 1; multiply by the element's volume or area):
///  - tetrahedra, 4 points, exact for polynomials of degree 2 (Hammer, Marlowe & Stroud 1956),
///    the rule of the standard 10-node hybrid tetrahedron: the stiffness of a straight P2 tet
///    (gradients linear, products quadratic) and the P1-pressure coupling are integrated
///    exactly; energy and convergence rates of P2 (O(h²) in the energy norm) need degree 2;
///  - tetrahedra, 125 points, exact for degree 7 (a conical product rule): the consistent mass
///    matrix, also of curved elements;
///  - triangles, 6 points, exact for degree 4 (Dunavant, "High degree efficient symmetrical
///    Gaussian quadrature rules for the triangle", IJNME 21, 1985): follower pressure on a
///    curved deformed face (shape function × area normal, degree 2 + 2).

#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/mesh.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Local vertex pairs of the six edge midpoints of a 10-node tet (nodes 4..9).
inline constexpr int kTetEdges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
/// Local vertex pairs of the three edge midpoints of a 6-node triangle (nodes 3..5).
inline constexpr int kTriangleEdges[3][2] = {{0, 1}, {1, 2}, {0, 2}};

/// Node indices of 10-node tets, one column per element.
using QuadraticTetNodes = Eigen::Matrix<int, 10, Eigen::Dynamic>;

/// A P1 tet mesh elevated to P2. Plain data, copyable and movable.
struct QuadraticTets {
  /// The P1 mesh's nodes, numbered as there (so node-indexed fields of the linear mesh read
  /// the vertex nodes directly), then one node per edge.
  Index num_vertices = 0;
  Points rest = Points(3, 0);  ///< 3 by num_nodes() rest positions
  QuadraticTetNodes elements = QuadraticTetNodes(10, 0);
  /// The two vertices of each edge node: column k is edge node num_vertices + k.
  Eigen::Matrix2Xi edges = Eigen::Matrix2Xi(2, 0);

  [[nodiscard]] Index num_nodes() const { return rest.cols(); }
  [[nodiscard]] Index num_elements() const { return elements.cols(); }
  /// The edge node between vertices a and b (either order), or -1 if they share no edge.
  [[nodiscard]] int EdgeNode(int a, int b) const;

  std::unordered_map<std::uint64_t, int> edge_index;  ///< key min·2³² + max → edge node

  /// Edge nodes placed off their edge's midpoint by a second-order mesh, and per element
  /// whether any of its edges is curved (empty when none is).
  Index num_curved_edges = 0;
  std::vector<std::uint8_t> curved;
  /// Whether element e has a curved edge: its map from the reference tet is not affine.
  [[nodiscard]] bool IsCurved(Index e) const;
};

/// Elevates the tets of `mesh` (its triangles are ignored) to P2: an edge node sits at the
/// position a second-order mesh gives it (`Mesh::edge_nodes`, curved edges) or else at the
/// edge's midpoint (straight edges; a middle node within 1e-12 of the edge's length of the
/// midpoint counts as straight and is put exactly there).
/// Throws InputError if the mesh has no tets. O(tets) with a hash map of the edges.
[[nodiscard]] QuadraticTets ElevateToQuadratic(const Mesh& mesh);

/// Values (10) of the P2 tet shape functions at barycentric point L.
[[nodiscard]] Eigen::Matrix<double, 10, 1> QuadraticTetShape(const Eigen::Vector4d& L);
/// Derivatives ∂N_a/∂L_k (10 by 4) at barycentric point L; ∇N_a = Σ_k ∂N_a/∂L_k ∇L_k.
[[nodiscard]] Eigen::Matrix<double, 10, 4> QuadraticTetShapeDerivatives(const Eigen::Vector4d& L);
/// Values (6) of the P2 triangle shape functions at barycentric point L (3).
[[nodiscard]] Eigen::Matrix<double, 6, 1> QuadraticTriangleShape(const Vec3& L);
/// ∂N_a/∂ξ and ∂N_a/∂η (columns) of the P2 triangle for the parametrisation L = (1 − ξ − η,
/// ξ, η), at barycentric point L.
[[nodiscard]] Eigen::Matrix<double, 6, 2> QuadraticTriangleParamDerivatives(const Vec3& L);

/// A quadrature rule on the reference simplex: barycentric points and weights summing to 1.
struct TetQuadrature {
  std::vector<Eigen::Vector4d> points;
  std::vector<double> weights;
};
struct TriangleQuadrature {
  std::vector<Vec3> points;
  std::vector<double> weights;
};
/// The 4-point degree-2 tet rule (above).
[[nodiscard]] const TetQuadrature& TetRuleDegree2();
/// A 125-point rule exact for polynomials of degree 7 (a conical product of Gauss rules,
/// positive weights): the consistent mass of a curved P2 tet (N_a N_b det J, degree 4 + 3).
[[nodiscard]] const TetQuadrature& TetRuleDegree7();
/// The 6-point degree-4 triangle rule (above).
[[nodiscard]] const TriangleQuadrature& TriangleRuleDegree4();

}  // namespace gipsi
GIPSI_EXPORT_END
