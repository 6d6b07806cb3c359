#include "gipsi/geometry/quality.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Geometry>

namespace gipsi {

double TetSignedVolume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

TetQualityReport CheckTetQuality(const Points& nodes, const Tets& tets,
                                 double degenerate_tolerance) {
  TetQualityReport report;
  report.num_tets = tets.cols();
  if (tets.cols() == 0) return report;
  report.min_volume = std::numeric_limits<double>::infinity();
  report.max_volume = -std::numeric_limits<double>::infinity();
  report.min_aspect = std::numeric_limits<double>::infinity();
  double aspect_sum = 0;
  int num_aspect = 0;
  // Normalisation of the aspect ratio: the regular tet has inradius L / (2·sqrt(6)).
  const double kRegular = 2.0 * std::sqrt(6.0);
  for (Index e = 0; e < tets.cols(); ++e) {
    const Vec3 x[4] = {nodes.col(tets(0, e)), nodes.col(tets(1, e)), nodes.col(tets(2, e)),
                       nodes.col(tets(3, e))};
    const double volume = TetSignedVolume(x[0], x[1], x[2], x[3]);
    report.min_volume = std::min(report.min_volume, volume);
    report.max_volume = std::max(report.max_volume, volume);
    report.total_volume += volume;
    double longest = 0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) longest = std::max(longest, (x[a] - x[b]).norm());
    if (volume < 0) report.inverted.push_back(int(e));
    if (std::abs(volume) <= degenerate_tolerance * longest * longest * longest) {
      report.degenerate.push_back(int(e));
      continue;
    }
    // Inradius r = 3|V| / (sum of face areas).
    const double area_sum =
        0.5 * ((x[1] - x[0]).cross(x[2] - x[0]).norm() + (x[1] - x[0]).cross(x[3] - x[0]).norm() +
               (x[2] - x[0]).cross(x[3] - x[0]).norm() + (x[2] - x[1]).cross(x[3] - x[1]).norm());
    const double inradius = 3.0 * std::abs(volume) / area_sum;
    const double aspect = longest / (kRegular * inradius);
    report.min_aspect = std::min(report.min_aspect, aspect);
    if (aspect > report.max_aspect) {
      report.max_aspect = aspect;
      report.worst_aspect_tet = int(e);
    }
    aspect_sum += aspect;
    ++num_aspect;
  }
  if (num_aspect > 0) {
    report.mean_aspect = aspect_sum / num_aspect;
  } else {
    report.min_aspect = 0;
  }
  return report;
}

}  // namespace gipsi
