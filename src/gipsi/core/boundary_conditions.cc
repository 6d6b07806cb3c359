#include "gipsi/core/boundary_conditions.h"

#include <algorithm>

#include "gipsi/base/error.h"

namespace gipsi {

BoundaryConditions::BoundaryConditions(Index num_vertices, Index num_faces)
    : kind_(static_cast<std::size_t>(3 * num_vertices), ConstraintKind::kFree),
      value_(Points::Zero(3, num_vertices)),
      force_(Points::Zero(3, num_vertices)),
      coupling_force_(Points::Zero(3, num_vertices)),
      traction_(Points::Zero(3, num_faces)),
      pressure_(VecX::Zero(num_faces)),
      coupling_pressure_(VecX::Zero(num_faces)) {}

void BoundaryConditions::PrescribeDisplacement(Index v, const Vec3& u, AxisMask axes) {
  GIPSI_CHECK(v >= 0 && v < num_vertices(), "boundary vertex {} out of range", v);
  for (int a = 0; a < 3; ++a) {
    if (axes & (1 << a)) {
      kind_[static_cast<std::size_t>(3 * v + a)] = ConstraintKind::kDisplacement;
      value_(a, v) = u[a];
    }
  }
}

void BoundaryConditions::PrescribeVelocity(Index v, const Vec3& vel, AxisMask axes) {
  GIPSI_CHECK(v >= 0 && v < num_vertices(), "boundary vertex {} out of range", v);
  for (int a = 0; a < 3; ++a) {
    if (axes & (1 << a)) {
      kind_[static_cast<std::size_t>(3 * v + a)] = ConstraintKind::kVelocity;
      value_(a, v) = vel[a];
    }
  }
}

void BoundaryConditions::Release(Index v, AxisMask axes) {
  GIPSI_CHECK(v >= 0 && v < num_vertices(), "boundary vertex {} out of range", v);
  for (int a = 0; a < 3; ++a) {
    if (axes & (1 << a)) {
      kind_[static_cast<std::size_t>(3 * v + a)] = ConstraintKind::kFree;
      value_(a, v) = 0;
    }
  }
}

bool BoundaryConditions::any_constraint() const {
  return std::any_of(kind_.begin(), kind_.end(),
                     [](ConstraintKind k) { return k != ConstraintKind::kFree; });
}

void BoundaryConditions::ClearCouplingLoads() {
  coupling_force_.setZero();
  coupling_pressure_.setZero();
}

bool BoundaryConditions::any_face_load() const {
  return (pressure_.size() > 0 &&
          (pressure_.cwiseAbs().maxCoeff() > 0 || coupling_pressure_.cwiseAbs().maxCoeff() > 0)) ||
         (traction_.size() > 0 && traction_.cwiseAbs().maxCoeff() > 0);
}

}  // namespace gipsi
