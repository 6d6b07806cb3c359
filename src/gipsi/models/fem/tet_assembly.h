#pragma once
/// @file
/// Rest-geometry data and parallel assembly machinery for linear (P1) tetrahedra: shape-function
/// gradients and volumes, the 3×3-block sparsity pattern of node-coupled matrices (stiffness,
/// consistent mass), the value offsets each element scatters into, and a colouring of element
/// chunks (runs of consecutive elements) so that chunks of one colour share no node and can be
/// assembled in parallel without locks. Results are bit-identical for any thread count: every
/// matrix or vector entry receives its element contributions in the same order (colour by
/// colour, chunk by chunk within a colour, element order within a chunk), which depends on the
/// mesh only.
///
/// P1 tetrahedron: N_a(X) linear, ∇N_a constant; with Dm = [X1−X0, X2−X0, X3−X0],
/// rows 1..3 of Dm⁻¹ are ∇N_1..3 and ∇N_0 = −(∇N_1 + ∇N_2 + ∇N_3). The deformation gradient is
/// F = Σ_a x_a ⊗ ∇N_a, and nodal forces from a first Piola–Kirchhoff stress P are
/// f_a = −V P ∇N_a (V the rest volume).

#include <algorithm>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/mesh.h"
#include "gipsi/numerics/adaptive_parallel.h"
#include "gipsi/numerics/sparse/linear_solver.h"
#include "gipsi/numerics/sparse/team_barrier.h"

#ifdef _OPENMP
#include <omp.h>
#endif

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Precomputed data for one tet mesh. Immutable after construction; copyable and movable.
class TetAssembly {
 public:
  /// Loops over fewer elements run on the calling thread: starting a parallel region costs
  /// more than assembling a few hundred elements (and much more on a loaded machine).
  static constexpr int kMinParallelElements = 1024;

  /// Throws InputError naming the first elements if any tet is degenerate or inverted
  /// (non-positive rest volume), or if the mesh has no tets.
  explicit TetAssembly(const Mesh& mesh);

  [[nodiscard]] Index num_nodes() const { return num_nodes_; }
  [[nodiscard]] Index num_elements() const { return tets_.cols(); }
  [[nodiscard]] const Tets& tets() const { return tets_; }
  /// 3 by 4 shape-function gradients of element e (column a = ∇N_a) [1/m].
  [[nodiscard]] Eigen::Map<const Eigen::Matrix<double, 3, 4>> gradients(Index e) const {
    return Eigen::Map<const Eigen::Matrix<double, 3, 4>>(grad_.data() + 12 * e);
  }
  /// Rest volume of element e [m³] (> 0).
  [[nodiscard]] double volume(Index e) const { return volume_[e]; }
  [[nodiscard]] const VecX& volumes() const { return volume_; }

  /// Deformation gradient F = I + Σ_a u_a ⊗ ∇N_a of element e for node displacements `u`
  /// (3N, node-major). Working with displacements keeps F's round-off proportional to the
  /// deformation, not to the distance from the origin (stiff materials amplify it).
  [[nodiscard]] Mat3 DeformationGradient(Index e, const double* u) const {
    const auto g = gradients(e);
    Mat3 f = Mat3::Identity();
    for (int a = 0; a < 4; ++a)
      f.noalias() += Eigen::Map<const Vec3>(u + 3 * tets_(a, e)) * g.col(a).transpose();
    return f;
  }

  /// A 3N by 3N matrix with the block pattern of node adjacency (both triangles, all nine
  /// entries of each coupled node pair) and zero values. Every node-coupled matrix of this mesh
  /// uses this pattern, so value arrays of different matrices align entry by entry.
  [[nodiscard]] SparseMatrix MakePattern() const;
  /// Index into the values array of `MakePattern()` of entry (row 3·a'+i, column 3·b'+k), where
  /// a', b' are the global nodes of local nodes a, b of element e. Valid for i, k in 0..2.
  [[nodiscard]] int ValueIndex(Index e, int a, int b, int i, int k) const {
    const int node_b = tets_(b, e);
    return col_start_[static_cast<std::size_t>(3 * node_b + k)] +
           3 * block_pos_[static_cast<std::size_t>(16 * e + 4 * b + a)] + i;
  }
  /// Value indices of the diagonal entries (3N).
  [[nodiscard]] const std::vector<int>& diagonal_index() const { return diag_index_; }

  /// Consecutive elements per chunk (the last chunk may be shorter). Chunks keep the mesh's
  /// element order, so an element's scatter lands near its predecessor's (for a mesh numbered
  /// with locality); colouring single elements instead made every colour sweep the whole
  /// matrix, measured 3-5× slower assembly at 20k-80k tets.
  static constexpr int kChunkElements = 512;
  /// Chunks grouped by colour: colour c holds chunks colour_chunks()[colour_start()[c] ..
  /// colour_start()[c+1]), and no two of them share a node.
  [[nodiscard]] const std::vector<int>& colour_start() const { return colour_start_; }
  [[nodiscard]] const std::vector<int>& colour_chunks() const { return colour_chunks_; }
  [[nodiscard]] int num_colours() const { return static_cast<int>(colour_start_.size()) - 1; }

  /// Runs `fn(e)` for every element: colour by colour, the chunks of a colour spread over the
  /// team (chunk k of a colour to thread k mod team size), the elements of a chunk in order.
  /// `fn` may scatter into node-indexed storage without locks. One parallel region for all
  /// colours, the threads meeting between colours at a TeamBarrier: a region per colour cost
  /// each colour a wake-up of the sleeping thread through the kernel with
  /// OMP_WAIT_POLICY=passive (the 10.9k-tet heart's residual has six colours). Each node's sum
  /// is taken in the same order (colours, then the one chunk of a colour that holds it)
  /// whatever the team, so the bits do not depend on the thread count, and `team` (one per
  /// kind of `fn`: their costs differ) may run it serially beside a busy neighbour, where every
  /// wait would be for a descheduled thread (AdaptiveParallel).
  template <class Fn>
  void ForEachElementColoured(Fn&& fn, AdaptiveParallel& team) const {
    ForEachChunkColoured(
        [&](Index first, Index last) {
          for (Index e = first; e < last; ++e) fn(e);
        },
        team);
  }
  /// ForEachElementColoured by chunks: `fn(first, last)` must handle elements [first, last) in
  /// order (it may evaluate several of them together, e.g. in vector lanes, as long as it
  /// scatters them in element order).
  template <class Fn>
  void ForEachChunkColoured(Fn&& fn, AdaptiveParallel& team) const {
    const int ne = static_cast<int>(num_elements());
    // The k-th chunk in colour order (colours are runs of colour_chunks_).
    const auto run_chunk = [&](int k) {
      const int first = colour_chunks_[static_cast<std::size_t>(k)] * kChunkElements;
      const int last = std::min(first + kChunkElements, ne);
      fn(static_cast<Index>(first), static_cast<Index>(last));
    };
    const bool parallel = team.Begin(ne >= kMinParallelElements && MaxTeamThreads() > 1 &&
                                     num_colours() < static_cast<int>(colour_chunks_.size()));
    if (!parallel) {
      for (int k = 0; k < static_cast<int>(colour_chunks_.size()); ++k) run_chunk(k);
    } else {
      TeamBarrier barrier;
#pragma omp parallel
      {
        int size = 1, rank = 0;
#ifdef _OPENMP
        size = omp_get_num_threads();
        rank = omp_get_thread_num();
#endif
        for (int c = 0; c < num_colours(); ++c) {
          const int end = colour_start_[static_cast<std::size_t>(c) + 1];
          for (int k = colour_start_[static_cast<std::size_t>(c)] + rank; k < end; k += size)
            run_chunk(k);
          if (c + 1 < num_colours()) barrier.Wait(size);
        }
      }
    }
    team.End();
  }
  /// Runs `fn(e)` for every element in parallel (no scatter allowed: write per-element data).
  template <class Fn>
  void ForEachElement(Fn&& fn) const {
    const int n = static_cast<int>(num_elements());
    ForRange(0, n, n >= kMinParallelElements, [&](int e) { fn(static_cast<Index>(e)); });
  }

  /// Consistent mass matrix values (in MakePattern's layout) for density ρ [kg/m³]:
  /// M_ab = ρV/20 (1 + δ_ab) I₃.
  void AssembleConsistentMass(double density, VecX& values) const;
  /// Lumped (row-sum) masses per node, ρV/4 from each element (N).
  [[nodiscard]] VecX LumpedMass(double density) const;

 private:
  Index num_nodes_ = 0;
  Tets tets_;
  std::vector<double> grad_;  // 12 per element
  VecX volume_;
  std::vector<int> col_start_;   // 3N + 1
  std::vector<int> row_index_;   // pattern row indices
  std::vector<int> block_pos_;   // 16 per element: position of node a in node b's neighbours
  std::vector<int> diag_index_;  // 3N
  std::vector<int> colour_start_;
  std::vector<int> colour_chunks_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
