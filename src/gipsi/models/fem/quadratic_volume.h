#pragma once
/// @file
/// The volume enclosed by curved (6-node, P2) triangles, with its gradient and Hessian in the
/// node positions: the cavity of a MixedSolid, whose endocardium bends with its elements.
///
/// V = (1/3) ∮ (x − o) · n dA over the faces and the caps of their open rims (the divergence
/// theorem, exact for any closed surface and independent of the constant point o). Each face is
/// the isoparametric quadratic triangle x(ξ, η) = Σ_k N_k(ξ, η) x_k, n dA = x_ξ × x_η dξ dη, so
/// the integrand is a polynomial of degree 4 and the 6-point degree-4 rule integrates it
/// exactly: V, ∂V/∂x and ∂²V/∂x² are those of the curved surface, not of a faceted one.
///
/// An open surface (an endocardium cut at the base) is closed as EnclosedVolume closes a flat
/// one (enclosed_volume.h): each rim loop is capped by a fan of 6-node triangles from the loop's
/// vertex centroid c, one per rim edge (its curved edge, and straight edges to c). c moves with
/// the loop, so the caps' share of the gradient reaches every vertex of the loop. The Hessian
/// is given per face and leaves the caps out (their terms couple every rim node with every
/// other): exact for the free nodes when the rim is held, as a ventricle's base is.

#include <array>
#include <vector>

#include <Eigen/Core>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Node ids of 6-node triangles (vertices, then the midpoints of (0,1), (1,2), (0,2)).
using QuadraticTriangles = Eigen::Matrix<int, 6, Eigen::Dynamic>;
/// ∂²V/∂x² of one 6-node triangle, node-major (row 3a + i, column 3b + j).
using FaceHessian = Eigen::Matrix<double, 18, 18>;

/// Immutable once built; copyable.
class QuadraticEnclosedVolume {
 public:
  /// One rim edge of an open surface: vertex a → vertex b in the faces' orientation, and its
  /// middle node.
  struct RimEdge {
    int a = 0, b = 0, middle = 0;
  };
  QuadraticEnclosedVolume() = default;
  /// `faces` (node ids < num_nodes) oriented out of the cavity; `loops`: the rim loops of the
  /// faces (as EnclosedVolume finds them), empty for a closed surface; `origin`: the constant
  /// point o (round-off only: a point near the cavity).
  QuadraticEnclosedVolume(QuadraticTriangles faces, std::vector<std::vector<RimEdge>> loops,
                          Index num_nodes, const Vec3& origin);

  [[nodiscard]] const QuadraticTriangles& faces() const { return faces_; }
  /// The enclosed volume for node positions `x` (3 by num_nodes); if `gradient` is not null it
  /// is set to ∂V/∂x (3 by num_nodes, zero off the surface and its rims).
  double Compute(const Points& x, Points* gradient = nullptr) const;
  /// ∂²V/∂x² of face f's own term (its six nodes, in the order of faces().col(f)).
  [[nodiscard]] FaceHessian Hessian(Index f, const Points& x) const;

 private:
  QuadraticTriangles faces_;
  std::vector<std::vector<RimEdge>> loops_;
  Index num_nodes_ = 0;
  Vec3 origin_ = Vec3::Zero();
};

/// (1/3) ∫ (x − o) · n dA over one 6-node triangle with node positions `x` (columns) and, in
/// `gradient` (if not null), its derivative in each node position: the building block of
/// QuadraticEnclosedVolume, exposed for tests.
double QuadraticTriangleVolume(const Eigen::Matrix<double, 3, 6>& x, const Vec3& origin,
                               Eigen::Matrix<double, 3, 6>* gradient);

}  // namespace gipsi
GIPSI_EXPORT_END
