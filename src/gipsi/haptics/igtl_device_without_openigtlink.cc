// IgtlDevice in a build without OpenIGTLink (GIPSI_WITH_OPENIGTLINK=OFF; src/CMakeLists.txt
// compiles this file instead of igtl_device.cc). Scenes never get here: ParseIgtlDevice refuses
// an OpenIGTLink device at its JSON path. A program that constructs one directly gets the same
// refusal as an InputError.

#include "gipsi/base/build_info.h"
#include "gipsi/base/error.h"
#include "gipsi/haptics/igtl_device.h"

namespace gipsi {

struct IgtlDevice::Connection {};

IgtlDevice::IgtlDevice(const IgtlDeviceParams& params) : params_(params) {
  throw InputError(
      MissingFeature("an OpenIGTLink device", "OpenIGTLink", "GIPSI_WITH_OPENIGTLINK"));
}

IgtlDevice::~IgtlDevice() = default;

DevicePose IgtlDevice::Read(double /*t*/) noexcept { return {}; }

void IgtlDevice::Command(const Vec3& force, const Vec3& torque) noexcept {
  force_ = force;
  torque_ = torque;
}

void IgtlDevice::SendSurface(const Points&, const Triangles&, const std::string&) {}

}  // namespace gipsi
