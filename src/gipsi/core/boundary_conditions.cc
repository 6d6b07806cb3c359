#include "gipsi/core/boundary_conditions.h"

#include <algorithm>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {

BoundaryConditions::BoundaryConditions(Index num_vertices, Index num_faces)
    : coupling_force_(Points::Zero(3, num_vertices)), coupling_pressure_(VecX::Zero(num_faces)) {
  applied_.kind.assign(static_cast<std::size_t>(3 * num_vertices), ConstraintKind::kFree);
  applied_.value = Points::Zero(3, num_vertices);
  applied_.force = Points::Zero(3, num_vertices);
  applied_.traction = Points::Zero(3, num_faces);
  applied_.pressure = VecX::Zero(num_faces);
  Touch();
}

void BoundaryConditions::Touch() { applied_.stamp = NewStateStamp(); }

void BoundaryConditions::SetApplied(const Applied& applied) {
  GIPSI_CHECK(applied.kind.size() == applied_.kind.size() &&
                  applied.pressure.size() == applied_.pressure.size(),
              "boundary conditions of another object");
  if (applied.stamp != applied_.stamp) applied_ = applied;
}

void BoundaryConditions::RestoreApplied(StateReader& in) {
  Applied read = applied_;
  ReadFields(in, read);
  applied_ = std::move(read);
  Touch();
  ClearCouplingLoads();
}

void BoundaryConditions::RestoreApplied(Applied applied) {
  GIPSI_CHECK(applied.kind.size() == applied_.kind.size() &&
                  applied.pressure.size() == applied_.pressure.size(),
              "boundary conditions of another store");
  applied_ = std::move(applied);
  Touch();
  ClearCouplingLoads();
}

namespace {

// BoundaryConditions::Applied's fields, of whatever shape they were written.
struct AnyShapeApplied {
  BoundaryConditions::Applied value;
  template <class Self, class V>
  static void Fields(Self& s, V& v) {
    v("kind", s.value.kind, Shape::kAny);
    v("value", s.value.value, Shape::kAny);
    v("force", s.value.force, Shape::kAny);
    v("traction", s.value.traction, Shape::kAny);
    v("pressure", s.value.pressure, Shape::kAny);
  }
};

}  // namespace

BoundaryConditions::Applied BoundaryConditions::ReadAnySize(StateReader& in) {
  AnyShapeApplied read;
  ReadFields(in, read);
  const Applied& a = read.value;
  const auto vertices = static_cast<std::size_t>(a.value.cols());
  if (a.kind.size() != 3 * vertices || a.value.rows() != 3 || a.force.rows() != 3 ||
      static_cast<std::size_t>(a.force.cols()) != vertices || a.traction.rows() != 3 ||
      a.traction.cols() != a.pressure.size())
    in.Fail("boundary conditions of inconsistent sizes: a corrupted checkpoint");
  for (const ConstraintKind k : a.kind)
    if (k != ConstraintKind::kFree && k != ConstraintKind::kDisplacement &&
        k != ConstraintKind::kVelocity)
      in.Fail("a boundary condition of unknown kind: a corrupted checkpoint");
  return std::move(read.value);
}

bool BoundaryConditions::AppliesNothing(const Applied& a) {
  return std::ranges::all_of(a.kind, [](ConstraintKind k) { return k == ConstraintKind::kFree; }) &&
         a.force.isZero(0) && a.traction.isZero(0) && a.pressure.isZero(0);
}

void BoundaryConditions::Applied::VertexRow(Index v, double* row) const {
  for (int a = 0; a < 3; ++a) {
    row[a] = static_cast<double>(kind[static_cast<std::size_t>(3 * v + a)]);
    row[3 + a] = value(a, v);
    row[6 + a] = force(a, v);
  }
}

void BoundaryConditions::Applied::SetVertexRow(Index v, const double* row) {
  for (int a = 0; a < 3; ++a) {
    kind[static_cast<std::size_t>(3 * v + a)] = static_cast<ConstraintKind>(row[a]);
    value(a, v) = row[3 + a];
    force(a, v) = row[6 + a];
  }
}

void BoundaryConditions::Applied::FaceRow(Index f, double* row) const {
  for (int a = 0; a < 3; ++a) row[a] = traction(a, f);
  row[3] = pressure[f];
}

void BoundaryConditions::Applied::SetFaceRow(Index f, const double* row) {
  for (int a = 0; a < 3; ++a) traction(a, f) = row[a];
  pressure[f] = row[3];
}

void BoundaryConditions::PrescribeDisplacement(Index v, const Vec3& u, AxisMask axes) {
  GIPSI_CHECK(v >= 0 && v < num_vertices(), "boundary vertex {} out of range", v);
  for (int a = 0; a < 3; ++a) {
    if (axes & (1 << a)) {
      applied_.kind[static_cast<std::size_t>(3 * v + a)] = ConstraintKind::kDisplacement;
      applied_.value(a, v) = u[a];
    }
  }
  Touch();
}

void BoundaryConditions::PrescribeVelocity(Index v, const Vec3& vel, AxisMask axes) {
  GIPSI_CHECK(v >= 0 && v < num_vertices(), "boundary vertex {} out of range", v);
  for (int a = 0; a < 3; ++a) {
    if (axes & (1 << a)) {
      applied_.kind[static_cast<std::size_t>(3 * v + a)] = ConstraintKind::kVelocity;
      applied_.value(a, v) = vel[a];
    }
  }
  Touch();
}

void BoundaryConditions::Release(Index v, AxisMask axes) {
  GIPSI_CHECK(v >= 0 && v < num_vertices(), "boundary vertex {} out of range", v);
  for (int a = 0; a < 3; ++a) {
    if (axes & (1 << a)) {
      applied_.kind[static_cast<std::size_t>(3 * v + a)] = ConstraintKind::kFree;
      applied_.value(a, v) = 0;
    }
  }
  Touch();
}

bool BoundaryConditions::any_constraint() const {
  return std::any_of(applied_.kind.begin(), applied_.kind.end(),
                     [](ConstraintKind k) { return k != ConstraintKind::kFree; });
}

void BoundaryConditions::ClearCouplingLoads() {
  coupling_force_.setZero();
  coupling_pressure_.setZero();
}

bool BoundaryConditions::any_face_load() const {
  const VecX& pressure = applied_.pressure;
  const Points& traction = applied_.traction;
  return (pressure.size() > 0 &&
          (pressure.cwiseAbs().maxCoeff() > 0 || coupling_pressure_.cwiseAbs().maxCoeff() > 0)) ||
         (traction.size() > 0 && traction.cwiseAbs().maxCoeff() > 0);
}

}  // namespace gipsi
