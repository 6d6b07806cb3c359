#include "gipsi/haptics/virtual_device.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "gipsi/base/error.h"

namespace gipsi {

VirtualDevice::VirtualDevice(std::vector<DeviceKeyframe> path) : path_(std::move(path)) {
  if (path_.empty()) throw InputError("virtual device: the trajectory has no keyframe");
  for (std::size_t i = 1; i < path_.size(); ++i)
    if (!(path_[i].time > path_[i - 1].time))
      throw InputError(fmt::format(
          "virtual device: keyframe times must increase strictly (keyframe {} at t = {} follows "
          "t = {})",
          i, path_[i].time, path_[i - 1].time));
}

std::vector<DeviceKeyframe> VirtualDevice::ReadTrajectory(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) ThrowInputError(file.string(), "", "cannot open trajectory file for reading");
  std::vector<DeviceKeyframe> path;
  std::string line;
  int number = 0;
  bool seen_content = false;
  while (std::getline(in, line)) {
    ++number;
    std::replace(line.begin(), line.end(), ',', ' ');
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    std::vector<double> values;
    std::string token;
    bool numeric = true;
    while (fields >> token) {
      char* end = nullptr;
      const double v = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0' || !std::isfinite(v)) {
        numeric = false;
        break;
      }
      values.push_back(v);
    }
    const std::string where = fmt::format("line {}", number);
    if (!numeric) {
      // The first content line may be a header if it does not start with a number.
      if (!seen_content && values.empty()) {
        seen_content = true;
        continue;
      }
      ThrowInputError(file.string(), where, "expected numbers: t, x, y, z[, buttons]");
    }
    seen_content = true;
    if (values.size() != 4 && values.size() != 5)
      ThrowInputError(
          file.string(), where,
          fmt::format("expected 4 or 5 values (t, x, y, z[, buttons]), got {}", values.size()));
    DeviceKeyframe k;
    k.time = values[0];
    k.position = Vec3(values[1], values[2], values[3]);
    if (values.size() == 5) {
      if (values[4] < 0 || values[4] != std::floor(values[4]) || values[4] > 4294967295.0)
        ThrowInputError(file.string(), where, "buttons must be a non-negative integer mask");
      k.buttons = static_cast<std::uint32_t>(values[4]);
    }
    if (!path.empty() && !(k.time > path.back().time))
      ThrowInputError(file.string(), where, "times must increase strictly");
    path.push_back(k);
  }
  if (path.empty()) ThrowInputError(file.string(), "", "the trajectory has no keyframe");
  return path;
}

DevicePose VirtualDevice::Read(double t) noexcept {
  DevicePose pose;
  pose.connected = connected_;
  if (t <= path_.front().time) {
    pose.position = path_.front().position;
    pose.buttons = path_.front().buttons;
    return pose;
  }
  if (t >= path_.back().time) {
    pose.position = path_.back().position;
    pose.buttons = path_.back().buttons;
    return pose;
  }
  // First keyframe later than t (binary search: no allocation).
  const auto it =
      std::upper_bound(path_.begin(), path_.end(), t,
                       [](double time, const DeviceKeyframe& k) { return time < k.time; });
  const DeviceKeyframe& b = *it;
  const DeviceKeyframe& a = *(it - 1);
  const double w = (t - a.time) / (b.time - a.time);
  pose.position = (1 - w) * a.position + w * b.position;
  pose.buttons = a.buttons;
  return pose;
}

void VirtualDevice::Command(const Vec3& force, const Vec3& torque) noexcept {
  force_ = force;
  torque_ = torque;
  ++commands_;
}

}  // namespace gipsi
