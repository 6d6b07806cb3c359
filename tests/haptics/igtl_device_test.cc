// The OpenIGTLink haptic device against a test server on the loopback interface (127.0.0.1
// only): the server's messages are packed and unpacked with the OpenIGTLink library itself; its
// socket is plain POSIX so that it listens on 127.0.0.1 alone (the library's ServerSocket binds
// every interface). Every wait is bounded (kWait); a failure never hangs the suite.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <igtlMessageHeader.h>
#include <igtlPolyDataMessage.h>
#include <igtlStatusMessage.h>
#include <igtlTransformMessage.h>

#include "gipsi/base/error.h"
#include "gipsi/haptics/haptic_tick.h"
#include "gipsi/haptics/igtl_device.h"
#include "gipsi/haptics/igtl_surface_sender.h"
#include "gipsi/io/builtins.h"
#include "gipsi/io/scene.h"
#include "haptics/no_allocation_guard.h"
#include "io/scene_test_util.h"

namespace gipsi {
namespace {

using ::testing::HasSubstr;
constexpr auto kWait = std::chrono::seconds(5);

// Polls `done` every millisecond for at most kWait; returns whether it became true.
bool WaitFor(const std::function<bool()>& done) {
  const auto end = std::chrono::steady_clock::now() + kWait;
  while (std::chrono::steady_clock::now() < end) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return done();
}

// A one-client OpenIGTLink server on 127.0.0.1 at an ephemeral port.
class LoopbackServer {
 public:
  explicit LoopbackServer(bool listen = true) {
    listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = 0;
    EXPECT_EQ(::bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
    socklen_t length = sizeof(a);
    ::getsockname(listener_, reinterpret_cast<sockaddr*>(&a), &length);
    port_ = ntohs(a.sin_port);
    if (listen) {
      EXPECT_EQ(::listen(listener_, 1), 0);
    }
  }
  ~LoopbackServer() {
    CloseClient();
    ::close(listener_);
  }
  LoopbackServer(const LoopbackServer&) = delete;
  LoopbackServer& operator=(const LoopbackServer&) = delete;

  [[nodiscard]] int port() const { return port_; }
  // Accepts the device's connection (bounded).
  bool Accept() {
    pollfd p{listener_, POLLIN, 0};
    if (::poll(&p, 1, 5000) <= 0) return false;
    client_ = ::accept(listener_, nullptr, nullptr);
    return client_ >= 0;
  }
  void CloseClient() {
    if (client_ >= 0) ::close(client_);
    client_ = -1;
  }
  bool Send(igtl::MessageBase* message) const {
    message->Pack();
    const auto n = static_cast<ssize_t>(message->GetPackSize());
    return ::send(client_, message->GetPackPointer(), static_cast<std::size_t>(n), MSG_NOSIGNAL) ==
           n;
  }
  bool SendTransform(const char* name, const igtl::Matrix4x4& m) const {
    auto message = igtl::TransformMessage::New();
    message->SetDeviceName(name);
    igtl::Matrix4x4 copy;
    std::memcpy(copy, m, sizeof(copy));
    message->SetMatrix(copy);
    return Send(message.GetPointer());
  }
  // Receives exactly n bytes (bounded).
  bool Receive(void* data, int n) const {
    char* out = static_cast<char*>(data);
    while (n > 0) {
      pollfd p{client_, POLLIN, 0};
      if (::poll(&p, 1, 5000) <= 0) return false;
      const ssize_t got = ::recv(client_, out, static_cast<std::size_t>(n), 0);
      if (got <= 0) return false;
      out += got;
      n -= static_cast<int>(got);
    }
    return true;
  }
  // Receives one POLYDATA message (bounded); null on failure or another message type.
  igtl::PolyDataMessage::Pointer ReceivePolyData() const {
    auto header = igtl::MessageHeader::New();
    header->InitPack();
    if (!Receive(header->GetPackPointer(), header->GetPackSize())) return nullptr;
    header->Unpack();
    if (std::strcmp(header->GetDeviceType(), "POLYDATA") != 0) return nullptr;
    auto poly = igtl::PolyDataMessage::New();
    poly->SetMessageHeader(header);
    poly->AllocatePack();
    if (!Receive(poly->GetPackBodyPointer(), poly->GetPackBodySize())) return nullptr;
    if (!(poly->Unpack(1) & igtl::MessageHeader::UNPACK_BODY)) return nullptr;
    return poly;
  }

 private:
  int listener_ = -1, client_ = -1, port_ = 0;
};

IgtlDeviceParams Params(int port) {
  IgtlDeviceParams p;
  p.host = "127.0.0.1";
  p.port = port;
  p.device_name = "Tool";
  p.reconnect_interval = 0.05;
  return p;
}

// A rigid transform whose entries are exact in float32: a rotation by a quarter turn about an
// axis (entries 0 and ±1) or about z by the angle with cos = 0.6, sin = 0.8 (entries are the
// floats nearest to 0.6 and 0.8), and a translation [mm] of multiples of 1/8.
void MakePose(int k, igtl::Matrix4x4& m) {
  igtl::IdentityMatrix(m);
  const float c = k % 2 == 0 ? 0.6F : 0.0F, s = k % 2 == 0 ? 0.8F : 1.0F;
  m[0][0] = c;
  m[0][1] = -s;
  m[1][0] = s;
  m[1][1] = c;
  m[0][3] = 10.125F * static_cast<float>(k);
  m[1][3] = -3.5F + static_cast<float>(k);
  m[2][3] = 42.0F - 0.25F * static_cast<float>(k);
}

TEST(IgtlDevice, ReportsExactlyTheTransformsOfItsDeviceName) {
  LoopbackServer server;
  IgtlDevice device(Params(server.port()));
  ASSERT_TRUE(server.Accept());
  EXPECT_TRUE(device.connected());
  EXPECT_FALSE(device.Read(0).connected);  // no pose yet: the watchdog keeps the force off
  for (int k = 0; k < 6; ++k) {
    // Before each pose of "Tool": a transform of another device and a STATUS message, both
    // ignored (the stream is in order, so they are consumed before the pose that follows).
    igtl::Matrix4x4 other;
    MakePose(100 + k, other);
    ASSERT_TRUE(server.SendTransform("Other", other));
    auto status = igtl::StatusMessage::New();
    status->SetDeviceName("Tool");
    status->SetCode(igtl::StatusMessage::STATUS_OK);
    ASSERT_TRUE(server.Send(status.GetPointer()));
    igtl::Matrix4x4 m;
    MakePose(k, m);
    ASSERT_TRUE(server.SendTransform("Tool", m));
    ASSERT_TRUE(WaitFor([&] { return device.num_poses() == k + 1; })) << "pose " << k;
    const DevicePose pose = device.Read(0);
    EXPECT_TRUE(pose.connected);
    // Exact: the position is the message's float translation times the length unit, as
    // documented; the orientation is the float rotation matrix's quaternion.
    const Vec3 expected = 0.001 * Vec3(m[0][3], m[1][3], m[2][3]);
    EXPECT_EQ(pose.position, expected) << "pose " << k;
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r(i, j) = m[i][j];
    EXPECT_EQ(pose.orientation.coeffs(), Eigen::Quaterniond(r).normalized().coeffs());
    // And it is the intended rotation (float entries: within 1e-7 of the exact one).
    const double angle = k % 2 == 0 ? std::atan2(0.8, 0.6) : M_PI / 2;
    EXPECT_LT(pose.orientation.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(angle, Vec3::UnitZ()))),
              1e-7);
  }
  EXPECT_EQ(device.num_poses(), 6);
  // Malformed poses (a NaN translation, an all-zero rotation) are dropped: the device keeps
  // reporting the last good pose, and the next good one is taken.
  igtl::Matrix4x4 bad;
  MakePose(7, bad);
  bad[1][3] = std::numeric_limits<float>::quiet_NaN();
  ASSERT_TRUE(server.SendTransform("Tool", bad));
  MakePose(8, bad);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) bad[i][j] = 0;
  ASSERT_TRUE(server.SendTransform("Tool", bad));
  igtl::Matrix4x4 good;
  MakePose(9, good);
  ASSERT_TRUE(server.SendTransform("Tool", good));
  ASSERT_TRUE(WaitFor([&] { return device.num_poses() == 7; }));
  EXPECT_EQ(device.Read(0).position, 0.001 * Vec3(good[0][3], good[1][3], good[2][3]));
  EXPECT_TRUE(device.Read(0).orientation.coeffs().allFinite());
}

TEST(IgtlDevice, SendsTheSurfaceAsPolyDataExactly) {
  LoopbackServer server;
  IgtlDevice device(Params(server.port()));
  ASSERT_TRUE(server.Accept());
  // A tetrahedron's surface [m]; points travel as float32(x / length_unit) [mm].
  Points x(3, 4);
  x << 0, 0.0125, 0, 0,  //
      0, 0, 0.02, 0,     //
      0, 0, 0, 0.0031;
  Triangles t(3, 4);
  t << 0, 0, 0, 1,  //
      2, 1, 3, 2,   //
      1, 3, 2, 3;
  device.SendSurface(x, t, "organ");
  const auto poly = server.ReceivePolyData();
  ASSERT_TRUE(poly);
  EXPECT_STREQ(poly->GetDeviceName(), "organ");
  ASSERT_EQ(poly->GetPoints()->GetNumberOfPoints(), 4);
  for (int i = 0; i < 4; ++i) {
    igtlFloat32 p[3];
    poly->GetPoints()->GetPoint(static_cast<unsigned>(i), p);
    for (int d = 0; d < 3; ++d)
      EXPECT_EQ(p[d], static_cast<float>(x(d, i) / 0.001)) << "point " << i << " axis " << d;
  }
  ASSERT_EQ(poly->GetPolygons()->GetNumberOfCells(), 4u);
  for (unsigned c = 0; c < 4; ++c) {
    ASSERT_EQ(poly->GetPolygons()->GetCellSize(c), 3u);
    igtlUint32 cell[3];
    poly->GetPolygons()->GetCell(c, cell);
    for (int d = 0; d < 3; ++d) EXPECT_EQ(cell[d], static_cast<igtlUint32>(t(d, c)));
  }
  EXPECT_TRUE(WaitFor([&] { return device.num_surfaces_sent() == 1; }));
}

TEST(IgtlDevice, LostConnectionFadesTheForceAndReconnects) {
  LoopbackServer server;
  IgtlDevice device(Params(server.port()));
  ASSERT_TRUE(server.Accept());
  igtl::Matrix4x4 m;
  igtl::IdentityMatrix(m);
  m[2][3] = -2;  // 2 mm below the plane z = 0
  ASSERT_TRUE(server.SendTransform("Tool", m));
  ASSERT_TRUE(WaitFor([&] { return device.num_poses() == 1; }));

  LatestValue<PlaneLocalModel> models;
  PlaneLocalModel& plane = models.back();
  plane.active = true;
  plane.stiffness = 500;  // N/m: 1 N at 2 mm
  ForceSafetyParams safety;
  safety.max_rate = 1e9;  // the fade alone shapes the force here
  HapticTick tick(device, DeviceWorkspace{}, models, safety);
  const double dt = 1e-3;
  double t = 0;
  for (int i = 0; i < 10; ++i, t += dt) {
    models.back().published_at = t;
    models.Publish();
    tick.Run(t, dt);
  }
  EXPECT_EQ(tick.safety().gain(), 1.0);
  EXPECT_NEAR(device.last_force().z(), 1.0, 1e-6);  // 500 N/m · float(2 mm)

  server.CloseClient();
  // (The device may reconnect at once: the listener completes the handshake by itself. Read
  // stays disconnected until a new pose arrives.)
  ASSERT_TRUE(WaitFor([&] { return device.num_disconnects() == 1; }));
  // Disconnected: the gain falls by dt / fade_time per tick (fade_time 0.1 s: 1 % per tick)
  // although the model stays fresh, and reaches zero after 100 ticks. The ticks (device reads
  // included) allocate nothing.
  std::vector<double> gains(120);
  {
    testing::NoAllocationGuard guard;
    for (int i = 0; i < 120; ++i, t += dt) {
      models.back().published_at = t;
      models.Publish();
      tick.Run(t, dt);
      gains[static_cast<std::size_t>(i)] = tick.safety().gain();
    }
  }
  for (int i = 1; i <= 120; ++i) {
    const double expected = std::max(0.0, 1.0 - i * dt / safety.fade_time);
    ASSERT_NEAR(gains[static_cast<std::size_t>(i - 1)], expected, 1e-12) << "tick " << i;
  }
  EXPECT_EQ(device.last_force(), Vec3::Zero());
  EXPECT_EQ(device.num_disconnects(), 1);

  // The device reconnects by itself; a new pose makes it connected again.
  ASSERT_TRUE(server.Accept());
  ASSERT_TRUE(server.SendTransform("Tool", m));
  ASSERT_TRUE(WaitFor([&] { return device.Read(t).connected; }));
}

TEST(IgtlDevice, RefusedOrBadConnectionsAreInputErrors) {
  LoopbackServer closed(/*listen=*/false);  // bound, not listening: connections are refused
  try {
    IgtlDevice device(Params(closed.port()));
    ADD_FAILURE() << "connected to a port nobody listens on";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("OpenIGTLink device at 127.0.0.1:" +
                                    std::to_string(closed.port()) + ": cannot connect within 2 s"));
  }
  // (No unknown-host case: resolving a name could leave the loopback interface.)
  IgtlDeviceParams p = Params(0);
  EXPECT_THROW(IgtlDevice{p}, InputError);
}

// --- scene files ---------------------------------------------------------------------------

std::string SceneText(const std::string& device, const std::string& extra_connector = "") {
  return R"({
  "meshes": {"box": {"generate": "box", "min": [0,0,0], "max": [0.02,0.02,0.02], "cells": [2,2,2]}},
  "objects": {
    "cube": {"type": "MassSpring", "domain": "box", "dt": 0.0002, "stiffness": 100,
             "boundary_conditions": [{"name": "bottom", "region": {"group": "zmin"}, "fix": true}]},
    "probe": {"type": "HapticProbe", "dt": 0.001, )" +
         device + R"(}
  },
  "connectors": {
    "haptics": {"type": "HapticCoupling", "object": "cube", "device": "probe"})" +
         extra_connector + R"(
  },
  "schedule": {"end": 0.1, "dt": 0.001}
})";
}

std::string LoadError(const std::string& text) { return testing::SceneLoadError(text); }

TEST(IgtlDeviceScene, SendsTheDeformedBoundaryOfTheNamedObject) {
  LoopbackServer server;
  const std::string device = R"("device": {"type": "OpenIGTLink", "port": )" +
                             std::to_string(server.port()) + R"(, "name": "Tool"})";
  TypeRegistry registry;
  RegisterBuiltins(registry);
  Scene scene = LoadSceneFromString(SceneText(device, R"(,
    "slicer": {"type": "OpenIGTLinkSurface", "object": "cube", "device": "probe", "rate": 1000})"),
                                    "igtl.json", ".", registry);
  ASSERT_TRUE(server.Accept());
  // Its port: the cube's boundary positions, read in metres (checked when the scene loaded).
  const Coordinator& coordinator = scene.kernel->coordinator();
  const Connector* slicer = nullptr;
  for (std::size_t i = 0; i < coordinator.num_connectors(); ++i)
    if (coordinator.connector(i).name() == "slicer") slicer = &coordinator.connector(i);
  ASSERT_NE(slicer, nullptr);
  ASSERT_EQ(slicer->ports().size(), 1u);
  EXPECT_EQ(slicer->ports()[0].object, &scene.kernel->FindObject("cube"));
  EXPECT_EQ(slicer->ports()[0].name, "boundary_position");
  EXPECT_EQ(slicer->ports()[0].access, FieldAccess::kRead);
  EXPECT_EQ(slicer->ports()[0].units, "m");
  // Connectors fire before the objects step: the surface sent at the firing of t = 0.02 is the
  // cube's boundary after the step to 0.02 (sagging under gravity from its fixed bottom).
  RunResult run = scene.kernel->Run(0.02);
  ASSERT_TRUE(run.ok()) << run.diagnostic;
  const SimObject& cube = scene.kernel->FindObject("cube");
  Points expected, rest;
  cube.boundary().Gather(cube.domain_positions(), expected);
  cube.boundary().Gather(cube.domain().nodes, rest);
  EXPECT_GT((expected - rest).norm(), 1e-9);  // it did deform
  run = scene.kernel->Run(0.021);
  ASSERT_TRUE(run.ok()) << run.diagnostic;
  // Only the newest queued surface is sent (older ones may be dropped): read until one equals
  // the expected surface; at most one message per firing.
  bool equal = false;
  for (int m = 0; m < 22 && !equal; ++m) {
    const auto poly = server.ReceivePolyData();
    ASSERT_TRUE(poly);
    EXPECT_STREQ(poly->GetDeviceName(), "cube");
    ASSERT_EQ(poly->GetPoints()->GetNumberOfPoints(), expected.cols());
    ASSERT_EQ(poly->GetPolygons()->GetNumberOfCells(),
              static_cast<igtlUint32>(cube.boundary().num_triangles()));
    equal = true;
    for (int i = 0; i < expected.cols(); ++i) {
      igtlFloat32 p[3];
      poly->GetPoints()->GetPoint(static_cast<unsigned>(i), p);
      for (int d = 0; d < 3; ++d)
        equal = equal && p[d] == static_cast<float>(expected(d, i) / 0.001);
    }
    for (unsigned c = 0; c < poly->GetPolygons()->GetNumberOfCells(); ++c) {
      igtlUint32 cell[3];
      poly->GetPolygons()->GetCell(c, cell);
      for (int d = 0; d < 3; ++d)
        equal = equal && cell[d] == static_cast<igtlUint32>(cube.boundary().triangles(d, c));
    }
  }
  EXPECT_TRUE(equal);
}

TEST(IgtlDeviceScene, BadKeysAreErrorsNamingTheJsonPath) {
  LoopbackServer closed(/*listen=*/false);
  const std::string port = std::to_string(closed.port());
  EXPECT_THAT(
      LoadError(SceneText(R"("path": [[0, 0, 0, 0.03]], "device": {"type": "OpenIGTLink"})")),
      HasSubstr("objects.probe: a HapticProbe needs exactly one of \"path\""));
  EXPECT_THAT(LoadError(SceneText(R"("device": {"type": "OpenIGTLink", "prot": 1})")),
              HasSubstr("objects.probe.device: unknown key 'prot' (did you mean 'port'?)"));
  EXPECT_THAT(LoadError(SceneText(R"("device": {"type": "OpenIGTLink", "port": 70000})")),
              HasSubstr("objects.probe.device.port: expected a TCP port in 1-65535"));
  EXPECT_THAT(LoadError(SceneText(R"("device": {"type": "Phantom"})")),
              HasSubstr("objects.probe.device.type"));
  EXPECT_THAT(LoadError(SceneText(R"("device": {"type": "OpenIGTLink", "length_unit": 0})")),
              HasSubstr("objects.probe.device.length_unit"));
  EXPECT_THAT(
      LoadError(SceneText(R"("device": {"type": "OpenIGTLink", "connect_timeout": 0.2, "port": )" +
                          port + "}")),
      HasSubstr("objects.probe.device: OpenIGTLink device at 127.0.0.1:" + port +
                ": cannot connect within 0.2 s"));
  EXPECT_THAT(LoadError(SceneText(R"("path": [[0, 0, 0, 0.03]])", R"(,
    "slicer": {"type": "OpenIGTLinkSurface", "object": "cube", "device": "probe"})")),
              HasSubstr("connectors.slicer.device: expected the name of a HapticProbe with an "
                        "OpenIGTLink device"));
}

}  // namespace
}  // namespace gipsi
