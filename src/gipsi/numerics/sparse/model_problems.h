#pragma once
/// @file
/// Symmetric positive definite model matrices with known structure, for tests and benchmarks
/// of the sparse solvers: a 3-D finite-difference Laplacian and a stiffness-shaped matrix of a
/// 3-D spring lattice (3 DOFs per node, 27-point node stencil, like trilinear hexahedral
/// elasticity). Both are built directly in compressed form, with both triangles stored.

#include <functional>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/numerics/sparse/linear_solver.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The 7-point Laplacian (6 on the diagonal, −1 to each grid neighbour, homogeneous Dirichlet
/// outside) on an n×n×n grid of unknowns, plus `shift`·I. n³ rows, lexicographic order (x
/// fastest). Its eigenvalues lie in [shift + λ₁, shift + 12 − λ₁] with λ₁ = 12·sin²(π/(2n + 2)),
/// so it is SPD for shift > −λ₁ and indefinite for shift = −1 when n ≥ 5. Requires n ≥ 1.
SparseMatrix MakeLaplacian3D(int n, double shift);

/// Spring stiffness at a point of the unit cube, > 0.
using StiffnessField = std::function<double(const Vec3&)>;

/// Stiffness matrix of an n×n×n lattice of nodes spanning the unit cube, 3 DOFs per node (DOF
/// 3·node + axis, node = x + n·(y + n·z)), each node joined to its 26 neighbours by an axial
/// spring of stiffness k(midpoint) (k = 1 when `stiffness` is empty): the spring from p to q
/// adds k·d dᵀ to the diagonal blocks and −k·d dᵀ to the off-diagonal ones, d = (q − p)/|q − p|.
/// Plus `shift`·I (a mass term; the lattice alone has the 6 rigid-body modes as null space), so
/// it is SPD for shift > 0. 3n³ rows and 9·(3n − 2)³ nonzeros. Requires n ≥ 2.
SparseMatrix MakeSpringLattice3D(int n, double shift, const StiffnessField& stiffness = {});

}  // namespace gipsi
GIPSI_EXPORT_END
