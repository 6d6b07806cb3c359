#pragma once
/// @file
/// Spring laws (material family "spring") for mass-spring models: the tension of a spring as a
/// function of its length L, rest length L0 and small-strain stiffness k.
///
///  - "Hooke":        T = k (L − L0).
///  - "Exponential":  T = (k L0 / b) (exp(b ε) − 1), ε = (L − L0) / L0, b > 0 — strain-stiffening
///                    like soft tissue (a Fung-type exponential law; Fung, "Biomechanics:
///                    Mechanical Properties of Living Tissues", 1993). Its small-strain stiffness
///                    is k, so it agrees with Hooke for small stretches.

#include <cmath>

#include "gipsi/base/export.h"
#include "gipsi/core/material.h"
#include "gipsi/core/registry.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// Not copyable; immutable after construction.
class SpringLaw : public Material {
 public:
  [[nodiscard]] std::string_view family() const final { return "spring"; }
  /// Tension [N] (positive when stretched).
  [[nodiscard]] virtual double Tension(double length, double rest_length, double k) const = 0;
  /// Stored energy [J], zero at rest.
  [[nodiscard]] virtual double Energy(double length, double rest_length, double k) const = 0;
  /// dT/dL [N/m] (the tangent stiffness).
  [[nodiscard]] virtual double TangentStiffness(double length, double rest_length,
                                                double k) const = 0;
};

class HookeSpring final : public SpringLaw {
 public:
  [[nodiscard]] std::string_view law() const override { return "Hooke"; }
  double Tension(double length, double rest_length, double k) const override {
    return k * (length - rest_length);
  }
  double Energy(double length, double rest_length, double k) const override {
    return 0.5 * k * (length - rest_length) * (length - rest_length);
  }
  double TangentStiffness(double, double, double k) const override { return k; }
};

class ExponentialSpring final : public SpringLaw {
 public:
  /// `b` > 0: the exponential stiffening rate (dimensionless).
  explicit ExponentialSpring(double b) : b_(b) {}
  [[nodiscard]] std::string_view law() const override { return "Exponential"; }
  [[nodiscard]] double b() const { return b_; }
  double Tension(double length, double rest_length, double k) const override {
    return k * rest_length / b_ * std::expm1(b_ * (length - rest_length) / rest_length);
  }
  double Energy(double length, double rest_length, double k) const override {
    const double strain = (length - rest_length) / rest_length;
    return k * rest_length / b_ *
           (rest_length / b_ * std::expm1(b_ * strain) - (length - rest_length));
  }
  double TangentStiffness(double length, double rest_length, double k) const override {
    return k * std::exp(b_ * (length - rest_length) / rest_length);
  }

 private:
  double b_;
};

/// Registers "Hooke" and "Exponential".
void RegisterSpringLaws(TypeRegistry& registry);

}  // namespace gipsi
GIPSI_EXPORT_END
