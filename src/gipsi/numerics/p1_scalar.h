#pragma once
/// @file
/// Operators of a scalar field on linear (P1) tetrahedra: the stiffness of an anisotropic
/// diffusion K_ij = Σ_e V_e ∇φ_i · D_e ∇φ_j, the consistent mass M_ij = Σ_e V_e (1 + δ_ij)/20 and
/// the lumped (row-sum) mass m_i = Σ_e V_e/4. Used by the monodomain objects and by rule-based
/// fibre generation (a Laplace problem through the wall).

#include <functional>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/numerics/sparse/linear_solver.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Plain struct of matrices (both triangles stored, compressed) and the lumped mass.
struct P1ScalarOperators {
  SparseMatrix stiffness;
  SparseMatrix consistent_mass;  ///< empty unless asked for
  VecX lumped_mass;
};

/// Assembles the operators for nodes `nodes` (3 by N, multiplied by `length_scale` first, e.g.
/// 1e3 for metres → millimetres) and tets `tets` (4 by E), with diffusivity tensor
/// `diffusivity(e)` per element. Throws InputError naming the first degenerate tet.
P1ScalarOperators AssembleP1Scalar(const Points& nodes, const Tets& tets, double length_scale,
                                   const std::function<Mat3(Index)>& diffusivity,
                                   bool consistent_mass);

/// Gradients of the four barycentric functions of tet `e` (rows) and its volume (unscaled
/// coordinates). Throws InputError for a degenerate tet.
Eigen::Matrix<double, 4, 3> P1Gradients(const Points& nodes, const Tets& tets, Index e,
                                        double* volume = nullptr);

}  // namespace gipsi
GIPSI_EXPORT_END
