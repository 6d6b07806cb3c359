#pragma once
/// @file
/// `SolidDistribution`: what a `FemSolid` needs to run as one process's part of a solid split
/// over processes (MPI ranks). parallel/distributed_solid.h implements it with MPI and PETSc;
/// this interface keeps the models layer free of both.
///
/// The part is the process's tets and every node they use. Local nodes [0, num_owned_nodes())
/// are owned by this process, the others are copies of nodes owned elsewhere. The part's
/// element loops give partial sums at shared nodes (each process adds its own tets); a residual
/// is made whole by SumShared, after which every process holds the same value at a shared node,
/// so all take the same Newton steps. Norms and dot products count each unknown on its owner
/// (VectorReduction). The tangent stays each process's own partial matrix, and the linear
/// solver sums it over the processes.

#include <memory>
#include <span>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/geometry/boundary.h"
#include "gipsi/geometry/region.h"
#include "gipsi/numerics/newton.h"
#include "gipsi/numerics/sparse/linear_solver.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// The whole boundary's faces that a region selects, found on the parts. Plain struct.
struct WholeFaceSelection {
  std::vector<int> faces;  ///< their faces on the whole boundary (MakeBoundary's), ascending
  /// Those faces alone, in that order and with the whole boundary's vertex order; its
  /// vertices are the faces' whole-mesh nodes, ascending (vertex_to_node); no face_to_tet.
  BoundarySurface surface;
};

/// Abstract; implementations are collective where noted (every process calls them in the same
/// order).
class SolidDistribution : public VectorReduction {
 public:
  /// Local nodes owned by this process (the leading ones).
  [[nodiscard]] virtual Index num_owned_nodes() const = 0;
  [[nodiscard]] Index owned() const final { return 3 * num_owned_nodes(); }
  /// The part's boundary geometry: the faces of the whole mesh's boundary that belong to the
  /// part's tets, and as vertices every local node on the whole boundary, also one that none of
  /// those faces uses. A condition on a shared boundary node then holds on every process that
  /// has the node, as the summed residual needs.
  [[nodiscard]] virtual const BoundarySurface& boundary() const = 0;
  /// Replaces each local node's three entries of `v` (3 per local node) by their sum over the
  /// processes that have the node. Collective.
  virtual void SumShared(VecX& v) const = 0;
  /// A solver of the whole system. Its Factorize takes this process's partial matrix (its tets'
  /// contributions in the local numbering; the processes' matrices are summed), its Solve a
  /// right-hand side that agrees at shared entries and returns a solution that does too.
  /// `rest`: the rest positions of the local nodes (3 per node), for the rigid-body modes an
  /// algebraic multigrid coarsens. Throws InputError for options it cannot honour.
  [[nodiscard]] virtual std::unique_ptr<LinearSolver> MakeLinearSolver(
      const LinearSolverOptions& options, const VecX& rest) const = 0;
  /// Whether whole_mesh() and whole_boundary() are there: not for a part cut from blocks,
  /// which no process held whole.
  [[nodiscard]] virtual bool has_whole_mesh() const = 0;
  /// The whole boundary's faces that `region` selects as SelectBoundaryFaces would on the whole
  /// mesh (a face group's triangles, or the faces whose three vertices the region selects),
  /// each process selecting among its part's faces; the same on every process. Collective;
  /// O(the selection) per process. Throws InputError as SelectBoundaryFaces does.
  [[nodiscard]] virtual WholeFaceSelection SelectWholeFaces(const Region& region) const = 0;
  /// The whole mesh the part was cut from, and its boundary (MakeBoundary); only when
  /// has_whole_mesh().
  [[nodiscard]] virtual const Mesh& whole_mesh() const = 0;
  [[nodiscard]] virtual const BoundarySurface& whole_boundary() const = 0;
  /// The whole boundary's face of each face of boundary().
  [[nodiscard]] virtual std::span<const int> whole_face() const = 0;
  /// The whole mesh's node of each local node.
  [[nodiscard]] virtual std::span<const int> whole_node() const = 0;
  /// A local tet's identifier in the whole mesh (its Gmsh tag or whole-mesh index), for
  /// messages that every process gives alike.
  [[nodiscard]] virtual std::int64_t WholeTetId(Index local) const = 0;
};

}  // namespace gipsi
GIPSI_EXPORT_END
