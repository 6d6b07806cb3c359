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

#include "gipsi/base/math.h"

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
  BoundaryConditions() = default;
  /// Storage for `num_vertices` boundary vertices and `num_faces` boundary triangles.
  BoundaryConditions(Index num_vertices, Index num_faces);
  BoundaryConditions(const BoundaryConditions&) = delete;
  BoundaryConditions& operator=(const BoundaryConditions&) = delete;
  BoundaryConditions(BoundaryConditions&&) = default;
  BoundaryConditions& operator=(BoundaryConditions&&) = default;

  [[nodiscard]] Index num_vertices() const { return Index(kind_.size() / 3); }
  [[nodiscard]] Index num_faces() const { return pressure_.size(); }

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
    return kind_[static_cast<std::size_t>(3 * v + axis)];
  }
  /// Prescribed displacement or velocity of vertex v (meaningful on constrained axes only).
  [[nodiscard]] auto value(Index v) const { return value_.col(v); }
  /// True if any axis of any vertex is constrained.
  [[nodiscard]] bool any_constraint() const;

  // --- Applied loads (persistent) ---
  /// Sets (replaces) the applied nodal force on vertex v [N].
  void SetForce(Index v, const Vec3& f) { force_.col(v) = f; }
  /// Sets the applied traction on boundary face f [Pa = N/m²], a force per current area.
  void SetTraction(Index f, const Vec3& t) { traction_.col(f) = t; }
  /// Sets the applied pressure on boundary face f [Pa]; positive pushes against the outward
  /// normal (into the body).
  void SetPressure(Index f, double p) { pressure_[f] = p; }

  // --- Coupling loads (cleared every macro step by the kernel) ---
  void AddCouplingForce(Index v, const Vec3& f) { coupling_force_.col(v) += f; }
  void AddCouplingPressure(Index f, double p) { coupling_pressure_[f] += p; }
  void ClearCouplingLoads();

  /// Total nodal force (applied + coupling) on vertex v.
  [[nodiscard]] Vec3 force(Index v) const { return force_.col(v) + coupling_force_.col(v); }
  [[nodiscard]] auto traction(Index f) const { return traction_.col(f); }
  /// Total pressure (applied + coupling) on face f.
  [[nodiscard]] double pressure(Index f) const { return pressure_[f] + coupling_pressure_[f]; }
  /// True if any face carries a traction or pressure (lets objects skip the face loop).
  [[nodiscard]] bool any_face_load() const;

 private:
  std::vector<ConstraintKind> kind_;  // 3 per vertex
  Points value_ = Points(3, 0);
  Points force_ = Points(3, 0);
  Points coupling_force_ = Points(3, 0);
  Points traction_ = Points(3, 0);
  VecX pressure_;
  VecX coupling_pressure_;
};

}  // namespace gipsi
