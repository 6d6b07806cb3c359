#include "gipsi/models/fem/tet_assembly.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "gipsi/base/error.h"
#include "gipsi/geometry/quality.h"

namespace gipsi {
TetAssembly::TetAssembly(const Mesh& mesh) : num_nodes_(mesh.num_nodes()), tets_(mesh.tets) {
  const Index ne = tets_.cols();
  if (ne == 0) throw InputError("FEM domain has no tetrahedra");
  grad_.resize(static_cast<std::size_t>(12 * ne));
  volume_.resize(ne);
  std::vector<int> bad;
  for (Index e = 0; e < ne; ++e) {
    Mat3 dm;
    for (int c = 0; c < 3; ++c)
      dm.col(c) = mesh.nodes.col(tets_(c + 1, e)) - mesh.nodes.col(tets_(0, e));
    const double det = dm.determinant();
    volume_[e] = det / 6.0;
    // Relative test: a sliver whose volume is round-off compared with its edges is degenerate.
    const double scale = dm.colwise().norm().prod();
    if (!(det > 1e-12 * scale)) {
      bad.push_back(static_cast<int>(e));
      continue;
    }
    const Mat3 inv = dm.inverse();
    Eigen::Map<Eigen::Matrix<double, 3, 4>> g(grad_.data() + 12 * e);
    for (int a = 0; a < 3; ++a) g.col(a + 1) = inv.row(a).transpose();
    g.col(0) = -(g.col(1) + g.col(2) + g.col(3));
  }
  if (!bad.empty())
    throw InputError(fmt::format(
        "FEM domain: {} tetrahedra are inverted or degenerate (non-positive rest volume), "
        "e.g. tets {}; fix the mesh orientation or quality",
        bad.size(), mesh.TetIdList(bad)));

  // Node adjacency (sorted, including the node itself).
  std::vector<std::vector<int>> nbrs(static_cast<std::size_t>(num_nodes_));
  for (Index e = 0; e < ne; ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        nbrs[static_cast<std::size_t>(tets_(b, e))].push_back(tets_(a, e));
  for (auto& list : nbrs) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  col_start_.assign(static_cast<std::size_t>(3 * num_nodes_ + 1), 0);
  for (Index n = 0; n < num_nodes_; ++n)
    for (int k = 0; k < 3; ++k)
      col_start_[static_cast<std::size_t>(3 * n + k + 1)] =
          col_start_[static_cast<std::size_t>(3 * n + k)] +
          3 * static_cast<int>(nbrs[static_cast<std::size_t>(n)].size());
  row_index_.resize(static_cast<std::size_t>(col_start_.back()));
  diag_index_.resize(static_cast<std::size_t>(3 * num_nodes_));
  for (Index n = 0; n < num_nodes_; ++n) {
    const auto& list = nbrs[static_cast<std::size_t>(n)];
    const auto self =
        std::lower_bound(list.begin(), list.end(), static_cast<int>(n)) - list.begin();
    for (int k = 0; k < 3; ++k) {
      int* rows = row_index_.data() + col_start_[static_cast<std::size_t>(3 * n + k)];
      for (std::size_t p = 0; p < list.size(); ++p)
        for (int i = 0; i < 3; ++i) rows[3 * p + static_cast<std::size_t>(i)] = 3 * list[p] + i;
      diag_index_[static_cast<std::size_t>(3 * n + k)] =
          col_start_[static_cast<std::size_t>(3 * n + k)] + 3 * static_cast<int>(self) + k;
    }
  }
  if (col_start_.back() < 0) throw InputError("FEM domain too large for 32-bit sparse indices");
  block_pos_.resize(static_cast<std::size_t>(16 * ne));
  for (Index e = 0; e < ne; ++e)
    for (int b = 0; b < 4; ++b) {
      const auto& list = nbrs[static_cast<std::size_t>(tets_(b, e))];
      for (int a = 0; a < 4; ++a)
        block_pos_[static_cast<std::size_t>(16 * e + 4 * b + a)] = static_cast<int>(
            std::lower_bound(list.begin(), list.end(), tets_(a, e)) - list.begin());
    }

  // Greedy colouring of chunks: the smallest colour not used by a chunk sharing a node.
  const int chunks = static_cast<int>((ne + kChunkElements - 1) / kChunkElements);
  std::vector<std::vector<int>> node_chunks(static_cast<std::size_t>(num_nodes_));
  for (Index e = 0; e < ne; ++e)
    for (int a = 0; a < 4; ++a) {
      auto& list = node_chunks[static_cast<std::size_t>(tets_(a, e))];
      const int chunk = static_cast<int>(e / kChunkElements);
      if (list.empty() || list.back() != chunk) list.push_back(chunk);  // e increases
    }
  std::vector<int> colour(static_cast<std::size_t>(chunks), -1);
  std::vector<char> taken;
  int num_colours = 0;
  for (int k = 0; k < chunks; ++k) {
    taken.assign(static_cast<std::size_t>(num_colours) + 1, 0);
    const Index first = Index{k} * kChunkElements;
    const Index last = std::min<Index>(first + kChunkElements, ne);
    for (Index e = first; e < last; ++e)
      for (int a = 0; a < 4; ++a)
        for (int other : node_chunks[static_cast<std::size_t>(tets_(a, e))]) {
          const int c = colour[static_cast<std::size_t>(other)];
          if (c >= 0) taken[static_cast<std::size_t>(c)] = 1;
        }
    int c = 0;
    while (taken[static_cast<std::size_t>(c)]) ++c;
    colour[static_cast<std::size_t>(k)] = c;
    num_colours = std::max(num_colours, c + 1);
  }
  colour_start_.assign(static_cast<std::size_t>(num_colours + 1), 0);
  for (int c : colour) ++colour_start_[static_cast<std::size_t>(c + 1)];
  for (int c = 0; c < num_colours; ++c)
    colour_start_[static_cast<std::size_t>(c + 1)] += colour_start_[static_cast<std::size_t>(c)];
  colour_chunks_.resize(static_cast<std::size_t>(chunks));
  std::vector<int> fill(colour_start_.begin(), colour_start_.end() - 1);
  for (int k = 0; k < chunks; ++k)
    colour_chunks_[static_cast<std::size_t>(
        fill[static_cast<std::size_t>(colour[static_cast<std::size_t>(k)])]++)] = k;
}

SparseMatrix TetAssembly::MakePattern() const {
  const Index n = 3 * num_nodes_;
  SparseMatrix m(n, n);
  m.resizeNonZeros(static_cast<Index>(row_index_.size()));
  std::copy(col_start_.begin(), col_start_.end(), m.outerIndexPtr());
  std::copy(row_index_.begin(), row_index_.end(), m.innerIndexPtr());
  std::fill(m.valuePtr(), m.valuePtr() + row_index_.size(), 0.0);
  GIPSI_CHECK(m.isCompressed());
  return m;
}

void TetAssembly::AssembleConsistentMass(double density, VecX& values) const {
  values.setZero(static_cast<Index>(row_index_.size()));
  AdaptiveParallel once;  // assembled once: on the team
  ForEachElementColoured(
      [&](Index e) {
        const double m = density * volume_[e] / 20.0;
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b)
            for (int k = 0; k < 3; ++k) values[ValueIndex(e, a, b, k, k)] += (a == b ? 2 : 1) * m;
      },
      once);
}

VecX TetAssembly::LumpedMass(double density) const {
  VecX m = VecX::Zero(num_nodes_);
  for (Index e = 0; e < num_elements(); ++e)
    for (int a = 0; a < 4; ++a) m[tets_(a, e)] += density * volume_[e] / 4.0;
  return m;
}

}  // namespace gipsi
