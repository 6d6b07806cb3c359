#include "gipsi/geometry/spatial_grid.h"

#include "gipsi/base/error.h"

namespace gipsi {
namespace {

/// Upper bound on the number of cells along one axis and in total (memory guard).
constexpr double kMaxCellsPerAxis = 1024;
constexpr double kMaxCells = 4.0e6;

}  // namespace

SpatialGrid::SpatialGrid(const Points& box_min, const Points& box_max)
    : num_items_(box_min.cols()), box_min_(box_min), box_max_(box_max) {
  GIPSI_CHECK(box_min.cols() == box_max.cols(), "box_min has {} columns, box_max {}",
              box_min.cols(), box_max.cols());
  if (num_items_ == 0) return;
  const Vec3 lo = box_min.rowwise().minCoeff();
  const Vec3 hi = box_max.rowwise().maxCoeff();
  const Vec3 extent = hi - lo;
  const double diag = extent.norm();
  const double k = double(num_items_);

  // Cell size: about one cell per item over the axes with a real extent, but not smaller than
  // the mean item box, so that an item touches a handful of cells.
  double h = 0;
  if (diag > 0) {
    double measure = 1;
    int num_axes = 0;
    for (int a = 0; a < 3; ++a) {
      if (extent[a] > 1e-9 * diag) {
        measure *= extent[a];
        ++num_axes;
      }
    }
    h = std::pow(measure / k, 1.0 / num_axes);
    const double mean_item = (box_max - box_min).colwise().maxCoeff().mean();
    h = std::max(h, mean_item);
    h = std::max(h, diag / kMaxCellsPerAxis);
  }
  double total = 1;
  for (int a = 0; a < 3; ++a) {
    dims_[a] = h > 0 ? std::max(1, int(std::ceil(extent[a] / h))) : 1;
    total *= dims_[a];
  }
  // Shrink uniformly if the memory guard is hit (very elongated sets of tiny items).
  while (total > kMaxCells) {
    total = 1;
    for (int a = 0; a < 3; ++a) {
      dims_[a] = std::max(1, dims_[a] / 2);
      total *= dims_[a];
    }
  }
  origin_ = lo;
  for (int a = 0; a < 3; ++a) cell_size_[a] = extent[a] > 0 ? extent[a] / dims_[a] : 1.0;

  auto cell_range = [&](Index item, std::array<int, 3>& c0, std::array<int, 3>& c1) {
    for (int a = 0; a < 3; ++a) {
      const double t0 = (box_min(a, item) - origin_[a]) / cell_size_[a];
      const double t1 = (box_max(a, item) - origin_[a]) / cell_size_[a];
      c0[a] = std::clamp(int(std::floor(t0)), 0, dims_[a] - 1);
      c1[a] = std::clamp(int(std::floor(t1)), 0, dims_[a] - 1);
    }
  };
  const int num_cells = dims_[0] * dims_[1] * dims_[2];
  cell_start_.assign(std::size_t(num_cells) + 1, 0);
  std::array<int, 3> c0{}, c1{};
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<int> fill;
    if (pass == 1) {
      for (int c = 0; c < num_cells; ++c) cell_start_[c + 1] += cell_start_[c];
      cell_items_.resize(std::size_t(cell_start_[num_cells]));
      fill.assign(cell_start_.begin(), cell_start_.end() - 1);
    }
    for (Index item = 0; item < num_items_; ++item) {
      cell_range(item, c0, c1);
      for (int z = c0[2]; z <= c1[2]; ++z)
        for (int y = c0[1]; y <= c1[1]; ++y)
          for (int x = c0[0]; x <= c1[0]; ++x) {
            const int cell = CellIndex({x, y, z});
            if (pass == 0)
              ++cell_start_[cell + 1];
            else
              cell_items_[fill[cell]++] = int(item);
          }
    }
  }
}

}  // namespace gipsi
