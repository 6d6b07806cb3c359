#pragma once
/// @file
/// Loads on boundary triangles: follower pressure and traction, with their derivatives for the
/// implicit tangent. For a triangle (x0, x1, x2) let n₂ = (x1 − x0) × (x2 − x0) (twice the
/// area times the unit normal, outward for tet boundaries). Each vertex receives
///   pressure p [Pa]:   f_a = −p n₂ / 6       (follows the deformed normal; p > 0 pushes in)
///   traction t [Pa]:   f_a = t |n₂| / 6      (fixed direction, per current area)
/// With e1 = x1 − x0, e2 = x2 − x0 and [u]× the cross-product matrix,
///   ∂n₂/∂x1 = −[e2]×,  ∂n₂/∂x2 = [e1]×,  ∂n₂/∂x0 = [e2]× − [e1]×.
/// The exact load Jacobian is not symmetric face by face; summed over a closed surface under a
/// uniform pressure it is (the load derives from the potential −p·volume).

#include <Eigen/Core>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

using Mat99 = Eigen::Matrix<double, 9, 9>;

/// ∂n₂/∂x_b for b = 0, 1, 2 (3×3 each).
void AreaNormalDerivatives(const Vec3& x0, const Vec3& x1, const Vec3& x2, Mat3 out[3]);

/// Adds the three vertex loads of one face (pressure p and traction t) to f0, f1, f2.
void FaceLoads(const Vec3& x0, const Vec3& x1, const Vec3& x2, double p, const Vec3& t, Vec3& f0,
               Vec3& f1, Vec3& f2);

/// Exact ∂(f0, f1, f2)/∂(x0, x1, x2) of FaceLoads (9×9, block (a, b) = ∂f_a/∂x_b).
Mat99 FaceLoadJacobian(const Vec3& x0, const Vec3& x1, const Vec3& x2, double p, const Vec3& t);

}  // namespace gipsi
GIPSI_EXPORT_END
