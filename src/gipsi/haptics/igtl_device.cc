#include "gipsi/haptics/igtl_device.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <vector>

#include <fmt/format.h>
#include <igtlMessageHeader.h>
#include <igtlPolyDataMessage.h>
#include <igtlTransformMessage.h>

#include "gipsi/base/error.h"

namespace gipsi {

namespace {

using Clock = std::chrono::steady_clock;

// A body larger than this is taken as a protocol error (the connection is dropped). POLYDATA of a
// million points is ~12 MB; a tracker's messages are a few hundred bytes.
constexpr int kMaxBodyBytes = 64 << 20;
// Longest wait for the rest of a message once its first byte arrived, and for a send.
constexpr int kMessageTimeoutMs = 1000;
// How long the network thread waits for input before it checks for a surface to send or a stop.
constexpr int kPollMs = 5;

int Milliseconds(double seconds) { return std::max(1, static_cast<int>(seconds * 1000 + 0.5)); }

// Connects a non-blocking TCP socket to `address` within `timeout_ms`; returns the descriptor or
// -1 (errno-style reason in `why`).
int ConnectWithin(const sockaddr_in& address, int timeout_ms, std::string& why) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    why = std::strerror(errno);
    return -1;
  }
  int rc = ::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address));
  if (rc < 0 && errno == EINPROGRESS) {
    pollfd p{fd, POLLOUT, 0};
    rc = ::poll(&p, 1, timeout_ms);
    if (rc == 0) {
      why = "timed out";
      ::close(fd);
      return -1;
    }
    int error = 0;
    socklen_t length = sizeof(error);
    if (rc < 0 || ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length) < 0 || error != 0) {
      why = std::strerror(error != 0 ? error : errno);
      ::close(fd);
      return -1;
    }
  } else if (rc < 0) {
    why = std::strerror(errno);
    ::close(fd);
    return -1;
  }
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  return fd;
}

}  // namespace

/// The socket and the message objects of the network thread.
struct IgtlDevice::Connection {
  sockaddr_in address{};
  int fd = -1;
  igtl::MessageHeader::Pointer header = igtl::MessageHeader::New();
  igtl::TransformMessage::Pointer transform = igtl::TransformMessage::New();
  std::vector<char> scratch = std::vector<char>(1 << 16);

  // Reads exactly n bytes, waiting at most kMessageTimeoutMs for each chunk; false on end of
  // stream, error or timeout.
  bool ReadFully(void* data, int n) const {
    char* out = static_cast<char*>(data);
    while (n > 0) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, kMessageTimeoutMs) <= 0) return false;
      const ssize_t got = ::recv(fd, out, static_cast<std::size_t>(n), 0);
      if (got == 0) return false;
      if (got < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;
        return false;
      }
      out += got;
      n -= static_cast<int>(got);
    }
    return true;
  }
  bool Skip(int n) {
    while (n > 0) {
      const int chunk = std::min(n, static_cast<int>(scratch.size()));
      if (!ReadFully(scratch.data(), chunk)) return false;
      n -= chunk;
    }
    return true;
  }
  bool WriteFully(const void* data, int n) const {
    const char* in = static_cast<const char*>(data);
    while (n > 0) {
      pollfd p{fd, POLLOUT, 0};
      if (::poll(&p, 1, kMessageTimeoutMs) <= 0) return false;
      const ssize_t put = ::send(fd, in, static_cast<std::size_t>(n), MSG_NOSIGNAL);
      if (put < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;
        return false;
      }
      in += put;
      n -= static_cast<int>(put);
    }
    return true;
  }
};

IgtlDevice::IgtlDevice(const IgtlDeviceParams& params)
    : params_(params), connection_(std::make_unique<Connection>()) {
  DevicePose none;
  none.connected = false;
  latest_ = received_ = none;
  poses_.back() = none;
  poses_.Publish();
  const std::string where = fmt::format("OpenIGTLink device at {}:{}", params.host, params.port);
  if (params.port < 1 || params.port > 65535)
    throw InputError(fmt::format("{}: port must be in 1-65535", where));
  if (params.device_name.empty())
    throw InputError(fmt::format("{}: the device name is empty", where));
  if (!(params.length_unit > 0) || !(params.connect_timeout > 0) ||
      !(params.reconnect_interval > 0))
    throw InputError(fmt::format(
        "{}: length_unit, connect_timeout and reconnect_interval must be positive", where));
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const int rc = ::getaddrinfo(params.host.c_str(), nullptr, &hints, &found);
  if (rc != 0 || found == nullptr)
    throw InputError(
        fmt::format("{}: cannot resolve host '{}' ({})", where, params.host, gai_strerror(rc)));
  std::memcpy(&connection_->address, found->ai_addr, sizeof(sockaddr_in));
  ::freeaddrinfo(found);
  connection_->address.sin_port = htons(static_cast<std::uint16_t>(params.port));
  std::string why;
  connection_->fd = ConnectWithin(connection_->address, Milliseconds(params.connect_timeout), why);
  if (connection_->fd < 0)
    throw InputError(
        fmt::format("{}: cannot connect within {} s ({}); is the tracker or Slicer's "
                    "OpenIGTLink server running?",
                    where, params.connect_timeout, why));
  connected_.store(true);
  thread_ = std::thread([this] { Run(); });
}

IgtlDevice::~IgtlDevice() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  if (connection_->fd >= 0) ::close(connection_->fd);
}

DevicePose IgtlDevice::Read(double /*t*/) noexcept {
  if (poses_.Fetch()) latest_ = poses_.front();
  return latest_;
}

void IgtlDevice::Command(const Vec3& force, const Vec3& torque) noexcept {
  force_ = force;
  torque_ = torque;
}

void IgtlDevice::SendSurface(const Points& positions, const Triangles& triangles,
                             const std::string& name) {
  IgtlSurface& s = surfaces_.back();
  s.name = name;
  s.positions = positions;
  s.triangles = triangles;
  surfaces_.Publish();
}

void IgtlDevice::Run() {
  Connection& c = *connection_;
  auto next_attempt = Clock::now();
  while (!stop_.load(std::memory_order_relaxed)) {
    if (c.fd < 0) {
      if (Clock::now() < next_attempt) {
        std::this_thread::sleep_for(std::chrono::milliseconds(kPollMs));
        continue;
      }
      std::string why;
      c.fd = ConnectWithin(c.address, 200, why);
      if (c.fd < 0) {
        next_attempt =
            Clock::now() + std::chrono::duration_cast<Clock::duration>(
                               std::chrono::duration<double>(params_.reconnect_interval));
        continue;
      }
      connected_.store(true);
    }
    pollfd p{c.fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, kPollMs);
    if (ready < 0 && errno != EINTR) {
      Disconnect();
      continue;
    }
    if (ready > 0 && (p.revents & (POLLIN | POLLHUP | POLLERR)) != 0 && !ReceiveOne()) {
      Disconnect();
      continue;
    }
    if (!SendPending()) Disconnect();
  }
}

bool IgtlDevice::ReceiveOne() {
  Connection& c = *connection_;
  c.header->InitPack();
  if (!c.ReadFully(c.header->GetPackPointer(), c.header->GetPackSize())) return false;
  c.header->Unpack();
  const int body = c.header->GetBodySizeToRead();
  if (body < 0 || body > kMaxBodyBytes) return false;
  if (std::strcmp(c.header->GetDeviceType(), "TRANSFORM") != 0 ||
      params_.device_name != c.header->GetDeviceName())
    return c.Skip(body);
  c.transform->SetMessageHeader(c.header);
  c.transform->AllocatePack();
  if (!c.ReadFully(c.transform->GetPackBodyPointer(), c.transform->GetPackBodySize())) return false;
  // A body that fails its CRC is dropped; the stream itself is still in step.
  if (!(c.transform->Unpack(1) & igtl::MessageHeader::UNPACK_BODY)) return true;
  igtl::Matrix4x4 m;
  c.transform->GetMatrix(m);
  Mat3 rotation;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) rotation(i, j) = m[i][j];
  const Vec3 translation(m[0][3], m[1][3], m[2][3]);
  // A malformed pose (non-finite entries, or a rotation that is not one: float32 entries of a
  // rotation are orthonormal to ~1e-7, far inside 1e-3) is dropped, never passed on.
  if (!rotation.allFinite() || !translation.allFinite() ||
      !((rotation.transpose() * rotation - Mat3::Identity()).norm() < 1e-3) ||
      !(rotation.determinant() > 0))
    return true;
  received_.position = params_.length_unit * translation;
  received_.orientation = Eigen::Quaterniond(rotation).normalized();
  received_.connected = true;
  poses_.back() = received_;
  poses_.Publish();
  poses_received_.fetch_add(1);
  return true;
}

bool IgtlDevice::SendPending() {
  if (!surfaces_.Fetch()) return true;
  const IgtlSurface& s = surfaces_.front();
  Connection& c = *connection_;
  auto points = igtl::PolyDataPointArray::New();
  points->SetNumberOfPoints(static_cast<int>(s.positions.cols()));
  for (Index i = 0; i < s.positions.cols(); ++i) {
    const Vec3 x = s.positions.col(i) / params_.length_unit;
    points->SetPoint(static_cast<unsigned>(i), static_cast<igtlFloat32>(x.x()),
                     static_cast<igtlFloat32>(x.y()), static_cast<igtlFloat32>(x.z()));
  }
  auto polygons = igtl::PolyDataCellArray::New();
  for (Index t = 0; t < s.triangles.cols(); ++t) {
    igtlUint32 cell[3] = {static_cast<igtlUint32>(s.triangles(0, t)),
                          static_cast<igtlUint32>(s.triangles(1, t)),
                          static_cast<igtlUint32>(s.triangles(2, t))};
    polygons->AddCell(3, cell);
  }
  auto message = igtl::PolyDataMessage::New();
  message->SetDeviceName(s.name.c_str());
  message->SetPoints(points.GetPointer());
  message->SetPolygons(polygons.GetPointer());
  message->Pack();
  if (!c.WriteFully(message->GetPackPointer(), message->GetPackSize())) return false;
  surfaces_sent_.fetch_add(1);
  return true;
}

void IgtlDevice::Disconnect() {
  Connection& c = *connection_;
  if (c.fd >= 0) ::close(c.fd);
  c.fd = -1;
  connected_.store(false);
  disconnects_.fetch_add(1);
  received_.connected = false;
  poses_.back() = received_;
  poses_.Publish();
}

}  // namespace gipsi
