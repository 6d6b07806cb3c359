#include "gipsi/viz/camera.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gipsi/base/error.h"

namespace gipsi::viz {
namespace {

using ::testing::HasSubstr;

TEST(Camera, AzimuthAndElevationPlaceTheEye) {
  Camera camera;
  camera.target = Eigen::Vector3d(1, 2, 3);
  camera.distance = 2;
  camera.azimuth = 0;
  camera.elevation = 0;
  EXPECT_LT((camera.Eye() - Eigen::Vector3d(1, 0, 3)).norm(), 1e-12);  // on the -y side
  camera.azimuth = 90;
  EXPECT_LT((camera.Eye() - Eigen::Vector3d(3, 2, 3)).norm(), 1e-12);  // on the +x side
  camera.elevation = 90 - 1e-9;
  EXPECT_NEAR(camera.Eye().z(), 5, 1e-9);
}

TEST(Camera, ViewPutsTheTargetOnTheAxisAndKeepsZUp) {
  Camera camera;
  camera.target = Eigen::Vector3d(0.3, -0.2, 0.1);
  camera.distance = 4;
  camera.azimuth = -37;
  camera.elevation = 21;
  const Eigen::Matrix4f view = camera.View();
  const Eigen::Vector4f t = view * Eigen::Vector4f(0.3f, -0.2f, 0.1f, 1.0f);
  EXPECT_NEAR(t.x(), 0, 1e-6);  // float matrices
  EXPECT_NEAR(t.y(), 0, 1e-6);
  EXPECT_NEAR(t.z(), -4, 1e-5);
  // World up projects to screen up (positive y, no x).
  const Eigen::Vector4f up = view * Eigen::Vector4f(0, 0, 1, 0);
  EXPECT_NEAR(up.x(), 0, 1e-6);
  EXPECT_GT(up.y(), 0);
  // A rotation: lengths are kept.
  const Eigen::Vector4f v = view * Eigen::Vector4f(1, 2, 3, 0);
  EXPECT_NEAR(v.head<3>().norm(), std::sqrt(14.0), 1e-5);
}

TEST(Camera, FitToKeepsEveryCornerInViewWithOneNearTheEdge) {
  FrameBuffers frame;
  frame.surfaces.resize(1);
  frame.surfaces[0].positions = {0, 0, 0, 2, 0, 0, 0, 1, 0, 0, 0, 0.5f, 2, 1, 0.5f};
  const double aspect = 1.6;
  Camera camera;
  camera.azimuth = -50;
  camera.elevation = 30;
  camera.FitTo(frame, aspect);
  EXPECT_LT((camera.target - Eigen::Vector3d(1, 0.5, 0.25)).norm(), 1e-7);
  const Eigen::Matrix4f pv = camera.Projection(aspect) * camera.View();
  double widest = 0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector4f p =
        pv * Eigen::Vector4f(c & 1 ? 2.f : 0.f, c & 2 ? 1.f : 0.f, c & 4 ? 0.5f : 0.f, 1.f);
    widest = std::max({widest, double(std::abs(p.x() / p.w())), double(std::abs(p.y() / p.w()))});
  }
  // The 10 % margin: the outermost corner sits at 1/1.1 of the half-screen (float round-off).
  EXPECT_NEAR(widest, 1 / 1.1, 1e-5);
}

TEST(Camera, RayThroughAProjectedPointMeetsIt) {
  Camera camera;
  camera.target = Eigen::Vector3d(0.2, 0.1, -0.3);
  camera.distance = 3;
  camera.azimuth = 35;
  camera.elevation = -20;
  const double aspect = 1.5;
  const Eigen::Vector3d point(0.5, -0.4, 0.2);
  const Eigen::Vector4f clip =
      camera.Projection(aspect) * camera.View() * Eigen::Vector4f(0.5f, -0.4f, 0.2f, 1.0f);
  const auto [origin, dir] = camera.Ray(clip.x() / clip.w(), clip.y() / clip.w(), aspect);
  EXPECT_NEAR(dir.norm(), 1, 1e-12);
  // Distance from the point to the ray: float matrices, a few units of scene size.
  EXPECT_LT((point - origin).cross(dir).norm(), 1e-5);
  // The centre of the screen looks at the target.
  const auto [o, d] = camera.Ray(0, 0, aspect);
  EXPECT_LT((camera.target - o).cross(d).norm(), 1e-5);
  EXPECT_GT((camera.target - o).dot(d), 0);
}

TEST(ParseCamera, ReadsTwoOrThreeNumbersAndRejectsTheRest) {
  Camera camera;
  ParseCamera("30,-10", "--camera", camera);
  EXPECT_EQ(camera.azimuth, 30);
  EXPECT_EQ(camera.elevation, -10);
  EXPECT_FALSE(camera.distance_given);
  ParseCamera("0,45,2.5", "--camera", camera);
  EXPECT_EQ(camera.distance, 2.5);
  EXPECT_TRUE(camera.distance_given);
  for (const char* bad : {"30", "30,95", "a,b", "1,2,0", "1,2,3,4", "1,,2"}) {
    try {
      ParseCamera(bad, "--camera", camera);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("--camera: expected AZIMUTH,ELEVATION[,DISTANCE]")) << bad;
    }
  }
}

}  // namespace
}  // namespace gipsi::viz
