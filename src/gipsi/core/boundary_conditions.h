#pragma once
/// @file
/// Boundary conditions on an object's boundary geometry: GiPSi's boundary-coupling interface.
/// Scene files, scheduled events, connectors and (later) collision response write them; the
/// owning object reads them inside its step. Storage is preallocated per boundary vertex and per
/// boundary triangle, so writing a condition never allocates.
///
/// Two layers of loads: *applied* loads (from the scene and events; they persist) and *coupling*
/// loads (written by connectors; the kernel clears them at the start of every macro step before
/// the connectors fire). The object sees their sum. Kinematic constraints are one layer: the last
/// writer wins.

#include <cstdint>
#include <vector>

#include "gipsi/base/export.h"
#include "gipsi/base/math.h"
#include "gipsi/base/state_value.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Bit mask of constrained axes: 1 = x, 2 = y, 4 = z.
using AxisMask = std::uint8_t;
inline constexpr AxisMask kAllAxes = 7;

/// What holds one axis of one boundary vertex.
enum class ConstraintKind : std::uint8_t {
  kFree,          ///< no kinematic constraint
  kDisplacement,  ///< displacement from the rest position prescribed (0 = fixed)
  kVelocity,      ///< velocity prescribed
};

/// Not copyable (objects hand out references); movable.
class BoundaryConditions {
 public:
  /// The applied (persistent) part: constraints and applied loads, as a state value type
  /// (base/state_value.h) that object snapshots copy. `stamp` identifies the contents: every
  /// change draws a new process-wide stamp, so equal stamps mean equal contents and a snapshot
  /// copies only when they differ. Copyable.
  struct Applied {
    std::vector<ConstraintKind> kind;  // 3 per vertex
    Points value = Points(3, 0);       // prescribed displacement or velocity, 3 by vertices
    Points force = Points(3, 0);       // 3 by vertices [N]
    Points traction = Points(3, 0);    // 3 by faces [Pa]
    VecX pressure;                     // per face [Pa]
    std::uint64_t stamp = 0;

    /// Vertex `v`'s and face `f`'s conditions as rows of numbers (the constraint kinds as
    /// their values), so that they move between stores numbered differently (another rank's
    /// part, the whole boundary): kVertexRow values per vertex, kFaceRow per face. Setting a
    /// row does not draw a new stamp: the caller does.
    static constexpr int kVertexRow = 9, kFaceRow = 4;
    void VertexRow(Index v, double* row) const;
    void SetVertexRow(Index v, const double* row);
    void FaceRow(Index f, double* row) const;
    void SetFaceRow(Index f, const double* row);

    template <class Self, class V>
    static void Fields(Self& s, V& v) {
      v("kind", s.kind, Shape::kFixed);
      v("value", s.value, Shape::kFixed);
      v("force", s.force, Shape::kFixed);
      v("traction", s.traction, Shape::kFixed);
      v("pressure", s.pressure, Shape::kFixed);
    }
  };

  BoundaryConditions() = default;
  /// Storage for `num_vertices` boundary vertices and `num_faces` boundary triangles.
  BoundaryConditions(Index num_vertices, Index num_faces);
  BoundaryConditions(const BoundaryConditions&) = delete;
  BoundaryConditions& operator=(const BoundaryConditions&) = delete;
  BoundaryConditions(BoundaryConditions&&) = default;
  BoundaryConditions& operator=(BoundaryConditions&&) = default;

  [[nodiscard]] Index num_vertices() const { return Index(applied_.kind.size() / 3); }
  [[nodiscard]] Index num_faces() const { return applied_.pressure.size(); }

  // --- Kinematic constraints (vertex v in [0, num_vertices), checked) ---
  /// Holds the masked axes at the rest position (zero displacement).
  void Fix(Index v, AxisMask axes = kAllAxes) { PrescribeDisplacement(v, Vec3::Zero(), axes); }
  /// Prescribes displacement `u` (from the rest position) on the masked axes.
  void PrescribeDisplacement(Index v, const Vec3& u, AxisMask axes = kAllAxes);
  /// Prescribes velocity `vel` on the masked axes.
  void PrescribeVelocity(Index v, const Vec3& vel, AxisMask axes = kAllAxes);
  /// Frees the masked axes.
  void Release(Index v, AxisMask axes = kAllAxes);
  [[nodiscard]] ConstraintKind kind(Index v, int axis) const {
    return applied_.kind[static_cast<std::size_t>(3 * v + axis)];
  }
  /// Prescribed displacement or velocity of vertex v (meaningful on constrained axes only).
  [[nodiscard]] auto value(Index v) const { return applied_.value.col(v); }
  /// True if any axis of any vertex is constrained.
  [[nodiscard]] bool any_constraint() const;

  // --- Applied loads (persistent) ---
  /// Sets (replaces) the applied nodal force on vertex v [N].
  void SetForce(Index v, const Vec3& f) {
    applied_.force.col(v) = f;
    Touch();
  }
  /// Sets the applied traction on boundary face f [Pa = N/m²], a force per current area.
  void SetTraction(Index f, const Vec3& t) {
    applied_.traction.col(f) = t;
    Touch();
  }
  /// Sets the applied pressure on boundary face f [Pa]; positive pushes against the outward
  /// normal (into the body).
  void SetPressure(Index f, double p) {
    applied_.pressure[f] = p;
    Touch();
  }

  // --- Coupling loads (cleared every macro step by the kernel) ---
  void AddCouplingForce(Index v, const Vec3& f) { coupling_force_.col(v) += f; }
  void AddCouplingPressure(Index f, double p) { coupling_pressure_[f] += p; }
  void ClearCouplingLoads();

  /// Total nodal force (applied + coupling) on vertex v.
  [[nodiscard]] Vec3 force(Index v) const { return applied_.force.col(v) + coupling_force_.col(v); }
  [[nodiscard]] auto traction(Index f) const { return applied_.traction.col(f); }
  /// Total pressure (applied + coupling) on face f.
  [[nodiscard]] double pressure(Index f) const {
    return applied_.pressure[f] + coupling_pressure_[f];
  }
  /// True if any face carries a traction or pressure (lets objects skip the face loop).
  [[nodiscard]] bool any_face_load() const;

  /// The applied part (constraints and applied loads), without the coupling loads.
  [[nodiscard]] const Applied& applied() const { return applied_; }
  /// Replaces the applied part by `applied` (a snapshot of this object's, checked sizes); the
  /// coupling loads are kept. Copies nothing when the stamps agree.
  void SetApplied(const Applied& applied);
  /// Checkpoints: writes the applied part (state_value.h) / reads it back (checked sizes; a new
  /// stamp) and clears the coupling loads.
  void SaveApplied(StateWriter& out) const { WriteFields(out, applied_); }
  void RestoreApplied(StateReader& in);
  /// As RestoreApplied, from conditions already read (ReadAnySize, moved between stores): their
  /// sizes must be this store's (checked).
  void RestoreApplied(Applied applied);
  /// Reads what SaveApplied wrote for a store of any size (the stamp left 0).
  [[nodiscard]] static Applied ReadAnySize(StateReader& in);
  /// Whether `applied` applies nothing (every vertex free, no force, traction or pressure).
  [[nodiscard]] static bool AppliesNothing(const Applied& applied);
  /// Reads what SaveApplied wrote for a store of any size, and drops it; returns whether it
  /// applied nothing.
  static bool SkipApplied(StateReader& in) { return AppliesNothing(ReadAnySize(in)); }

 private:
  /// Marks the applied part as changed (a new stamp).
  void Touch();

  Applied applied_;
  Points coupling_force_ = Points(3, 0);
  VecX coupling_pressure_;
};

}  // namespace gipsi
GIPSI_EXPORT_END
