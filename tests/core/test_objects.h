#pragma once
// Small simulation objects for kernel and connector tests.

#include <limits>

#include "gipsi/core/sim_object.h"

namespace gipsi::testing {

/// A point object that counts its steps, holds a writable global 3-vector "value", and can be
/// told to diverge at a given step.
class CountingObject final : public SimObject {
 public:
  explicit CountingObject(std::string name, std::int64_t diverge_at = -1)
      : SimObject(std::move(name)), diverge_at_(diverge_at) {
    value_id_ = DeclareField(
        {"value", FieldLocation::kGlobal, 3, "1", FieldAccess::kReadWrite, "a test value"});
    time_id_ = DeclareField(
        {"clock", FieldLocation::kGlobal, 1, "s", FieldAccess::kRead, "the object's time"});
    value_.setZero();
  }
  std::string_view type_name() const override { return "Counting"; }
  const Points& domain_positions() const override { return positions_; }
  std::int64_t steps() const { return steps_; }
  const Vec3& value() const { return value_; }

 protected:
  StepStatus DoStep(double, double) override {
    ++steps_;
    if (steps_ == diverge_at_)
      return StepStatus::Diverged("test divergence", 7, std::numeric_limits<double>::quiet_NaN());
    return StepStatus::Ok();
  }
  void DoReadField(FieldId id, Eigen::Ref<Eigen::MatrixXd> out) const override {
    if (id == value_id_)
      out.col(0) = value_;
    else
      out(0, 0) = time();
  }
  void DoWriteField(FieldId, const Eigen::Ref<const Eigen::MatrixXd>& in) override {
    value_ = in.col(0);
  }

 private:
  std::int64_t diverge_at_;
  std::int64_t steps_ = 0;
  FieldId value_id_, time_id_;
  Vec3 value_;
  Points positions_ = Points(3, 0);
};

}  // namespace gipsi::testing
