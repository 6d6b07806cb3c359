#pragma once
/// @file
/// Small math types shared by every layer. Coordinates are 3-D column vectors; a set of N points
/// is a 3 by N matrix (column j is point j), as in Eigen's column-major layout.

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products everywhere

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

using Index = Eigen::Index;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using VecX = Eigen::VectorXd;
/// 3 by N point or vector set (column j belongs to item j).
using Points = Eigen::Matrix3Xd;
/// Triangle connectivity, 3 by T (column t holds the vertex indices of triangle t).
using Triangles = Eigen::Matrix<int, 3, Eigen::Dynamic>;
/// Tetrahedron connectivity, 4 by E (column e holds the node indices of tet e).
using Tets = Eigen::Matrix<int, 4, Eigen::Dynamic>;

}  // namespace gipsi
GIPSI_EXPORT_END
