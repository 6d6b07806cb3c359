#include "gipsi/viz/camera.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi::viz {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

}  // namespace

Eigen::Vector3d Camera::Eye() const {
  const double a = azimuth * kDegree, e = elevation * kDegree;
  // azimuth 0 puts the eye on -y (looking along +y), positive azimuth turns it towards +x.
  const Eigen::Vector3d dir(std::sin(a) * std::cos(e), -std::cos(a) * std::cos(e), std::sin(e));
  return target + distance * dir;
}

Eigen::Matrix4f Camera::View() const {
  const Eigen::Vector3d eye = Eye();
  const Eigen::Vector3d f = (target - eye).normalized();
  Eigen::Vector3d up(0, 0, 1);
  Eigen::Vector3d s = f.cross(up);
  if (s.norm() < 1e-9) s = Eigen::Vector3d(1, 0, 0);  // looking straight up or down
  s.normalize();
  const Eigen::Vector3d u = s.cross(f);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m.cast<float>();
}

Eigen::Matrix4f Camera::Projection(double aspect) const {
  const double near = distance * 0.01, far = distance * 10;
  const double t = 1.0 / std::tan(0.5 * fov_y * kDegree);
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = t / aspect;
  p(1, 1) = t;
  p(2, 2) = -(far + near) / (far - near);
  p(2, 3) = -2 * far * near / (far - near);
  p(3, 2) = -1;
  return p.cast<float>();
}

void Camera::FitTo(const FrameBuffers& frame, double aspect) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& surface : frame.surfaces)
    for (std::size_t v = 0; v < surface.num_vertices(); ++v)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], double(surface.positions[3 * v + std::size_t(k)]));
        hi[k] = std::max(hi[k], double(surface.positions[3 * v + std::size_t(k)]));
      }
  if (!(lo.array() <= hi.array()).all()) return;  // nothing to look at
  target = 0.5 * (lo + hi);
  if (distance_given) return;
  // The smallest distance at which every corner of the box projects inside 1/1.1 of the
  // half-screen (a 10 % margin): a corner at q from the target lies at depth D + f·q along the
  // view direction f, so it needs D >= 1.1 |s·q| / tan(half_x) - f·q and the same with u and
  // half_y; and it must stay in front of the near plane.
  const double saved = distance;
  distance = 1;
  const Eigen::Vector3d f = (target - Eye()).normalized();
  distance = saved;
  Eigen::Vector3d s = f.cross(Eigen::Vector3d::UnitZ());
  if (s.norm() < 1e-9) s = Eigen::Vector3d::UnitX();
  s.normalize();
  const Eigen::Vector3d u = s.cross(f);
  const double tan_y = std::tan(0.5 * fov_y * kDegree), tan_x = tan_y * aspect;
  double needed = 0, nearest = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p((corner & 1 ? hi : lo).x(), (corner & 2 ? hi : lo).y(),
                            (corner & 4 ? hi : lo).z());
    const Eigen::Vector3d q = p - target;
    needed = std::max(
        needed, 1.1 * std::max(std::abs(s.dot(q)) / tan_x, std::abs(u.dot(q)) / tan_y) - f.dot(q));
    nearest = std::max(nearest, -f.dot(q));
  }
  distance = std::max({needed, nearest + 0.1 * (hi - lo).norm(), 1e-9});
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> Camera::Ray(double ndc_x, double ndc_y,
                                                        double aspect) const {
  const Eigen::Matrix4d inverse = (Projection(aspect) * View()).cast<double>().inverse();
  auto unproject = [&](double z) {
    const Eigen::Vector4d p = inverse * Eigen::Vector4d(ndc_x, ndc_y, z, 1);
    return Eigen::Vector3d(p.head<3>() / p.w());
  };
  const Eigen::Vector3d near = unproject(-1), far = unproject(1);
  return {near, (far - near).normalized()};
}

void Camera::Orbit(double d_azimuth, double d_elevation) {
  azimuth = std::fmod(azimuth + d_azimuth, 360.0);
  elevation = std::clamp(elevation + d_elevation, -89.0, 89.0);
}

void ParseCamera(std::string_view text, std::string_view where, Camera& camera) {
  std::vector<double> values;
  std::size_t start = 0;
  bool ok = true;
  while (ok && start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string item(text.substr(start, comma - start));
    double value = 0;
    const auto [end, error] = std::from_chars(item.data(), item.data() + item.size(), value);
    ok = error == std::errc() && end == item.data() + item.size() && std::isfinite(value);
    values.push_back(value);
    start = comma + 1;
  }
  if (!ok || values.size() < 2 || values.size() > 3 || std::abs(values[1]) >= 90 ||
      (values.size() == 3 && !(values[2] > 0)))
    ThrowInputError("", where,
                    fmt::format("expected AZIMUTH,ELEVATION[,DISTANCE] in degrees (|elevation| < "
                                "90) and scene units (distance > 0), got '{}'",
                                text));
  camera.azimuth = values[0];
  camera.elevation = values[1];
  if (values.size() == 3) {
    camera.distance = values[2];
    camera.distance_given = true;
  }
}

}  // namespace gipsi::viz
