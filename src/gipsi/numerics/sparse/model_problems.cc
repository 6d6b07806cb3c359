// Model SPD matrices built straight into compressed columns (rows ascending in every column).

#include "gipsi/numerics/sparse/model_problems.h"

#include <array>
#include <limits>

#include "gipsi/base/error.h"

namespace gipsi {
namespace {

/// An empty n×n compressed matrix with room for `nnz` entries, to be filled through its arrays.
SparseMatrix EmptyCompressed(Index rows, Index nnz) {
  GIPSI_CHECK(nnz <= std::numeric_limits<int>::max(), "model matrix too large for int indices");
  SparseMatrix A(rows, rows);
  A.resizeNonZeros(nnz);
  return A;
}

}  // namespace

SparseMatrix MakeLaplacian3D(int n, double shift) {
  GIPSI_CHECK(n >= 1, "MakeLaplacian3D: n = {} < 1", n);
  const Index rows = Index{n} * n * n;
  const Index nnz = 7 * rows - 6 * Index{n} * n;  // each of the 3 axes loses 2 n² neighbours
  SparseMatrix A = EmptyCompressed(rows, nnz);
  int* outer = A.outerIndexPtr();
  int* inner = A.innerIndexPtr();
  double* values = A.valuePtr();
  const int stride[3] = {1, n, n * n};
  int k = 0;
  for (int z = 0; z < n; ++z) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const int c = x + n * (y + n * z);
        const int coord[3] = {x, y, z};
        outer[c] = k;
        auto add = [&](int row, double value) {
          inner[k] = row;
          values[k] = value;
          ++k;
        };
        for (int axis = 2; axis >= 0; --axis)  // rows below c, farthest first
          if (coord[axis] > 0) add(c - stride[axis], -1.0);
        add(c, 6.0 + shift);
        for (int axis = 0; axis < 3; ++axis)
          if (coord[axis] < n - 1) add(c + stride[axis], -1.0);
      }
    }
  }
  outer[rows] = k;
  GIPSI_CHECK(k == nnz);
  return A;
}

SparseMatrix MakeSpringLattice3D(int n, double shift, const StiffnessField& stiffness) {
  GIPSI_CHECK(n >= 2, "MakeSpringLattice3D: n = {} < 2", n);
  const Index nodes = Index{n} * n * n;
  const Index rows = 3 * nodes;
  const Index span = 3 * Index{n} - 2;  // neighbours-or-self pairs along one axis: n + 2(n − 1)
  const Index nnz = 9 * span * span * span;
  SparseMatrix A = EmptyCompressed(rows, nnz);
  int* outer = A.outerIndexPtr();
  int* inner = A.innerIndexPtr();
  double* values = A.valuePtr();
  const double h = 1.0 / (n - 1);

  struct Block {
    int node;
    Mat3 value;
  };
  std::array<Block, 27> blocks;
  int k = 0;
  for (int z = 0; z < n; ++z) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        const int c = x + n * (y + n * z);
        // Neighbours in ascending node order (z slowest), so rows come out sorted.
        int count = 0;
        int self = -1;
        Mat3 diagonal = shift * Mat3::Identity();
        for (int dz = -1; dz <= 1; ++dz) {
          for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
              const int qx = x + dx, qy = y + dy, qz = z + dz;
              if (qx < 0 || qy < 0 || qz < 0 || qx >= n || qy >= n || qz >= n) continue;
              Block& b = blocks[static_cast<std::size_t>(count)];
              b.node = qx + n * (qy + n * qz);
              if (dx == 0 && dy == 0 && dz == 0) {
                self = count++;
                continue;
              }
              const Vec3 offset(dx, dy, dz);
              const Vec3 d = offset.normalized();
              // The midpoint from integer coordinates: the same bits from either end, so the
              // matrix is exactly symmetric even where `stiffness` jumps at a midpoint.
              const Vec3 mid = (0.5 * h) * Vec3(x + qx, y + qy, z + qz);
              const double kspring = stiffness ? stiffness(mid) : 1.0;
              b.value = -kspring * d * d.transpose();
              diagonal -= b.value;
              ++count;
            }
          }
        }
        blocks[static_cast<std::size_t>(self)].value = diagonal;
        for (int a = 0; a < 3; ++a) {
          outer[3 * c + a] = k;
          for (int i = 0; i < count; ++i) {
            const Block& b = blocks[static_cast<std::size_t>(i)];
            for (int r = 0; r < 3; ++r) {
              inner[k] = 3 * b.node + r;
              values[k] = b.value(r, a);
              ++k;
            }
          }
        }
      }
    }
  }
  outer[rows] = k;
  GIPSI_CHECK(k == nnz);
  return A;
}

}  // namespace gipsi
