#pragma once
/// @file
/// Lookup tables of functions of one variable on a uniform grid with linear interpolation, as
/// ionic-model codes (CARP/openCARP and others) use for the many voltage-dependent rates: one
/// interpolation replaces several exp() calls. The error of linear interpolation is at most
/// dx²/8 · max|f''| per column; `MaxMidpointError` measures it.

#include <cstddef>
#include <functional>
#include <vector>

#include "gipsi/base/export.h"

GIPSI_EXPORT_BEGIN
namespace gipsi {

/// `num_columns` functions tabulated at x_min, x_min + dx, ..., x_max, row-major (the columns of
/// one x are contiguous, so an interpolation reads two adjacent rows). Immutable after
/// construction; copyable and movable.
class LookupTable {
 public:
  /// Fills row r with `fill(x_min + r dx, row)`. Preconditions (abort otherwise): x_max > x_min,
  /// dx > 0, num_columns ≥ 1, at most 10^7 rows.
  LookupTable(double x_min, double x_max, double dx, int num_columns,
              const std::function<void(double x, double* row)>& fill);

  [[nodiscard]] double x_min() const { return x_min_; }
  [[nodiscard]] double x_max() const { return x_min_ + dx_ * static_cast<double>(rows_ - 1); }
  [[nodiscard]] double dx() const { return dx_; }
  [[nodiscard]] std::size_t num_rows() const { return rows_; }
  [[nodiscard]] int num_columns() const { return columns_; }

  /// Where x falls: `row` is the grid row at or below x and `frac` in [0, 1] the weight of the
  /// next row. x outside [x_min, x_max] is clamped to it; NaN reads row 0. Tables built on the
  /// same grid (x_min, dx, rows) can share a Position.
  struct Position {
    std::size_t row;
    double frac;
  };
  [[nodiscard]] Position Locate(double x) const {
    double s = (x - x_min_) * inv_dx_;
    s = s > 0.0 ? s : 0.0;  // also maps NaN to 0
    s = s < last_ ? s : last_;
    const auto row = static_cast<std::size_t>(s);
    return {row, s - static_cast<double>(row)};
  }
  /// Column c interpolated at `position` (c < num_columns()).
  [[nodiscard]] double Interpolate(const Position& position, int c) const {
    const double* lo = data_.data() + position.row * static_cast<std::size_t>(columns_) + c;
    return *lo + position.frac * (lo[columns_] - *lo);
  }
  /// True if `other` has the same grid (its Positions are valid here).
  [[nodiscard]] bool SameGrid(const LookupTable& other) const {
    return x_min_ == other.x_min_ && dx_ == other.dx_ && rows_ == other.rows_;
  }
  /// All columns interpolated at x into out[0 .. num_columns()).
  void InterpolateAll(double x, double* out) const;

  /// The largest |interpolated − exact| over the midpoints of all grid intervals, per column,
  /// relative to max(|exact|, floor[c]) (pass 0 for purely relative errors).
  [[nodiscard]] std::vector<double> MaxMidpointError(
      const std::function<void(double x, double* row)>& exact,
      const std::vector<double>& floor) const;

 private:
  double x_min_, dx_, inv_dx_, last_;
  std::size_t rows_;
  int columns_;
  std::vector<double> data_;  // (rows_ + 1) × columns_: the last row repeats row rows_ − 1
};

}  // namespace gipsi
GIPSI_EXPORT_END
