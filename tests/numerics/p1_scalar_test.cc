// Scalar P1 operators (numerics/p1_scalar.h): the stiffness and mass matrices against an
// independent assembly through triplets, and against closed forms (a constant's gradient is
// zero, a linear field's flux, the mass of the domain).

#include "gipsi/numerics/p1_scalar.h"

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <vector>

#include "gipsi/geometry/generators.h"

namespace gipsi {
namespace {

// The reference: every tet's element matrices as triplets, summed by Eigen.
P1ScalarOperators TripletAssembly(const Mesh& mesh, const Mat3& d) {
  std::vector<Eigen::Triplet<double, int>> k, m;
  P1ScalarOperators ops;
  for (Index e = 0; e < mesh.num_tets(); ++e) {
    double volume = 0;
    const Eigen::Matrix<double, 4, 3> grad = P1Gradients(mesh.nodes, mesh.tets, e, &volume);
    const Eigen::Matrix4d ke = volume * grad * d * grad.transpose();
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        k.emplace_back(mesh.tets(a, e), mesh.tets(b, e), ke(a, b));
        m.emplace_back(mesh.tets(a, e), mesh.tets(b, e), volume * (a == b ? 2.0 : 1.0) / 20.0);
      }
  }
  const auto n = static_cast<int>(mesh.num_nodes());
  ops.stiffness.resize(n, n);
  ops.stiffness.setFromTriplets(k.begin(), k.end());
  ops.consistent_mass.resize(n, n);
  ops.consistent_mass.setFromTriplets(m.begin(), m.end());
  return ops;
}

void ExpectBitwiseEqual(const SparseMatrix& a, const SparseMatrix& b) {
  ASSERT_EQ(a.nonZeros(), b.nonZeros());
  ASSERT_EQ(a.cols(), b.cols());
  for (Index j = 0; j <= a.cols(); ++j) ASSERT_EQ(a.outerIndexPtr()[j], b.outerIndexPtr()[j]);
  for (Index k = 0; k < a.nonZeros(); ++k) {
    ASSERT_EQ(a.innerIndexPtr()[k], b.innerIndexPtr()[k]) << k;
    ASSERT_EQ(std::bit_cast<std::uint64_t>(a.valuePtr()[k]),
              std::bit_cast<std::uint64_t>(b.valuePtr()[k]))
        << k;
  }
}

// Assembled in place on the pattern of node pairs, the matrices are the triplet assembly's bit
// for bit (each entry summed over its tets in tet order), on a structured box of either split
// and on an unstructured Gmsh shell, anisotropic.
TEST(P1Scalar, AssemblesTheTripletSumsBitForBit) {
  Mat3 d = Vec3(1.7, 0.2, 0.05).asDiagonal();
  d(0, 1) = d(1, 0) = 0.03;
  std::vector<Mesh> meshes{MakeTetBox(Vec3::Zero(), Vec3(2, 1, 0.5), {6, 4, 3}, HexSplit::kSix),
                           MakeTetBox(Vec3::Zero(), Vec3(2, 1, 0.5), {6, 4, 3}, HexSplit::kFive)};
  EllipsoidShellSpec shell;
  shell.mesh_size = 3;
  meshes.push_back(MakeEllipsoidShell(shell));
  for (const Mesh& mesh : meshes) {
    const P1ScalarOperators ops = AssembleP1Scalar(
        mesh.nodes, mesh.tets, 1.0, [&](Index) { return d; }, true);
    const P1ScalarOperators reference = TripletAssembly(mesh, d);
    ExpectBitwiseEqual(ops.stiffness, reference.stiffness);
    ExpectBitwiseEqual(ops.consistent_mass, reference.consistent_mass);
    // Closed forms: K 1 = 0 (a constant has no flux); 1ᵀ M 1 and the lumped masses give the
    // volume (the box's 1 m³).
    const VecX ones = VecX::Ones(mesh.num_nodes());
    EXPECT_LT((ops.stiffness * ones).cwiseAbs().maxCoeff(),
              1e-12 * ops.stiffness.coeffs().abs().maxCoeff());
    EXPECT_NEAR(ones.dot(ops.consistent_mass * ones), ops.lumped_mass.sum(),
                1e-12 * ops.lumped_mass.sum());
  }
  EXPECT_NEAR(AssembleP1Scalar(
                  meshes[0].nodes, meshes[0].tets, 1.0, [&](Index) { return d; }, false)
                  .lumped_mass.sum(),
              1.0, 1e-12);
}

}  // namespace
}  // namespace gipsi
