#include "gipsi/models/ep/lookup_table.h"

#include <algorithm>
#include <cmath>

#include "gipsi/base/error.h"

namespace gipsi {

LookupTable::LookupTable(double x_min, double x_max, double dx, int num_columns,
                         const std::function<void(double x, double* row)>& fill)
    : x_min_(x_min), dx_(dx), inv_dx_(1.0 / dx), columns_(num_columns) {
  GIPSI_CHECK(x_max > x_min && dx > 0 && num_columns >= 1, "table [{}, {}] step {}", x_min, x_max,
              dx);
  const double intervals = std::ceil((x_max - x_min) / dx - 1e-9);
  GIPSI_CHECK(intervals < 1e7, "{} rows", intervals);
  rows_ = static_cast<std::size_t>(intervals) + 1;
  last_ = static_cast<double>(rows_ - 1);
  const auto width = static_cast<std::size_t>(columns_);
  data_.resize((rows_ + 1) * width);
  for (std::size_t r = 0; r < rows_; ++r)
    fill(x_min_ + dx_ * static_cast<double>(r), data_.data() + r * width);
  // Padding: x = x_max gives frac 0 on the last row and reads (but does not use) the next one.
  std::copy_n(data_.data() + (rows_ - 1) * width, width, data_.data() + rows_ * width);
}

void LookupTable::InterpolateAll(double x, double* out) const {
  const Position position = Locate(x);
  for (int c = 0; c < columns_; ++c) out[c] = Interpolate(position, c);
}

std::vector<double> LookupTable::MaxMidpointError(
    const std::function<void(double x, double* row)>& exact,
    const std::vector<double>& floor) const {
  GIPSI_CHECK(floor.size() == static_cast<std::size_t>(columns_), "{} floors for {} columns",
              floor.size(), columns_);
  std::vector<double> error(floor.size(), 0.0), want(floor.size()), got(floor.size());
  for (std::size_t r = 0; r + 1 < rows_; ++r) {
    const double x = x_min_ + dx_ * (static_cast<double>(r) + 0.5);
    exact(x, want.data());
    InterpolateAll(x, got.data());
    for (std::size_t c = 0; c < want.size(); ++c)
      error[c] =
          std::max(error[c], std::abs(got[c] - want[c]) / std::max(std::abs(want[c]), floor[c]));
  }
  return error;
}

}  // namespace gipsi
