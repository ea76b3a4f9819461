#include "render/camera_path.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "core/error.h"

namespace confluent {
namespace {


TEST(OrbitPath, CamerasCircleTheCentreAndLookAtIt) {
  OrbitPathOptions options;
  options.center_in_world = Eigen::Vector3d(0.3, -0.2, 1.1);
  options.radius_m = 2.5;
  options.height_m = 1.6;
  options.num_frames = 12;
  options.width_px = 320;
  options.height_px = 240;
  options.vertical_fov_deg = 40.0;
  const std::vector<Camera> path = OrbitPath(options);
  ASSERT_EQ(path.size(), 12u);
  for (int i = 0; i < 12; ++i) {
    const Camera& camera = path[i];
    EXPECT_NO_THROW(camera.Check());
    const Eigen::Vector3d c = camera.center_in_world();
    EXPECT_NEAR((c - options.center_in_world).head<2>().norm(), 2.5, 1e-9);
    EXPECT_NEAR(c.z(), 1.6, 1e-9);
    // The look-at point projects to the image centre and lies straight ahead.
    const Eigen::Vector2d pixel = camera.Project(options.center_in_world);
    EXPECT_NEAR(pixel.x(), (320 - 1) / 2.0, 1e-6);
    EXPECT_NEAR(pixel.y(), (240 - 1) / 2.0, 1e-6);
    EXPECT_GT(camera.PointInCamera(options.center_in_world).z(), 0.0);
    EXPECT_NEAR(camera.vertical_fov_deg(), 40.0, 0.05);
    // World up is image up: a point above the centre projects above it.
    EXPECT_LT(camera.Project(options.center_in_world + Eigen::Vector3d(0, 0, 0.1)).y(), pixel.y());
    // Equal azimuth steps of 30 degrees, counter-clockwise, starting in front (-y).
    const double azimuth = std::atan2(c.y() - options.center_in_world.y(), c.x() - options.center_in_world.x());
    const double expected = (-90.0 + 30.0 * i) * M_PI / 180.0;
    EXPECT_NEAR(std::remainder(azimuth - expected, 2 * M_PI), 0.0, 1e-9) << i;
  }
}

TEST(OrbitPath, PartialSweepEndsAtTheEndAngle) {
  OrbitPathOptions options;
  options.sweep_deg = -90.0;
  options.start_angle_deg = 0.0;
  options.num_frames = 4;
  const std::vector<Camera> path = OrbitPath(options);
  const Eigen::Vector3d last = path.back().center_in_world() - options.center_in_world;
  EXPECT_NEAR(last.x(), 0.0, 1e-9);
  EXPECT_NEAR(last.y(), -options.radius_m, 1e-9);
  options.num_frames = 0;
  EXPECT_THROW(OrbitPath(options), UsageError);
}

TEST(OrbitPath, FittedToARing) {
  std::vector<Camera> ring;
  for (int i = 0; i < 6; ++i) {
    const double a = 2 * M_PI * i / 6;
    ring.push_back(LookAtCamera("c" + std::to_string(i), Eigen::Vector3d(3 * std::cos(a), 3 * std::sin(a), 1.8),
                                Eigen::Vector3d(0, 0, 1), 200, 100, 150));
  }
  const OrbitPathOptions options = OrbitAroundCameras(ring, Eigen::Vector3d(0, 0, 1));
  EXPECT_NEAR(options.radius_m, 3.0, 1e-9);
  EXPECT_NEAR(options.height_m, 1.8, 1e-9);
  EXPECT_EQ(options.width_px, 200);
  EXPECT_EQ(options.height_px, 100);
  EXPECT_NEAR(options.vertical_fov_deg, ring[0].vertical_fov_deg(), 1e-9);
}

std::vector<Camera> KeyCameras() {
  std::vector<Camera> keys;
  const Eigen::Vector3d target(0, 0, 1);
  const double angles[] = {-80.0, -20.0, 35.0, 110.0};
  for (int j = 0; j < 4; ++j) {
    const double a = angles[j] * M_PI / 180.0;
    Camera camera = LookAtCamera("key" + std::to_string(j),
                                 Eigen::Vector3d(3.0 * std::cos(a), 3.0 * std::sin(a), 1.2 + 0.2 * j), target, 160,
                                 120, 140.0 + 10.0 * j);
    camera.dist << -0.1, 0.01, 0, 0, 0;
    keys.push_back(camera);
  }
  return keys;
}

TEST(PathThroughCameras, PassesExactlyThroughTheKeys) {
  const std::vector<Camera> keys = KeyCameras();
  KeyCameraPathOptions options;
  options.num_frames = 31;
  const std::vector<Camera> path = PathThroughCameras(keys, options);
  ASSERT_EQ(path.size(), 31u);
  const std::vector<int> at = KeyFrameIndices(4, options);
  ASSERT_EQ(at, (std::vector<int>{0, 10, 20, 30}));
  for (int j = 0; j < 4; ++j) {
    const Camera& camera = path[at[j]];
    EXPECT_LT((camera.center_in_world() - keys[j].center_in_world()).norm(), 1e-12) << j;
    EXPECT_LT((camera.rotation - keys[j].rotation).norm(), 1e-12) << j;
    EXPECT_LT((camera.K - keys[j].K).norm(), 1e-12) << j;
    EXPECT_FALSE(camera.has_distortion());
  }
  // In between: proper rotations, small steps (smooth), intrinsics between the keys'.
  for (std::size_t i = 0; i < path.size(); ++i) {
    EXPECT_NO_THROW(path[i].Check());
    EXPECT_GE(path[i].K(0, 0), 140.0 - 1e-9);
    EXPECT_LE(path[i].K(0, 0), 170.0 + 1e-9);
    if (i > 0) {
      const double step = (path[i].center_in_world() - path[i - 1].center_in_world()).norm();
      EXPECT_LT(step, 0.6) << i;
      EXPECT_GT(step, 0.05) << i;
      const double turn = Eigen::AngleAxisd(path[i].rotation * path[i - 1].rotation.transpose()).angle();
      EXPECT_LT(turn, 15.0 * M_PI / 180.0) << i;
    }
  }
  // Midway between two keys the camera still looks roughly at the common target.
  const Camera& middle = path[15];
  const Eigen::Vector2d pixel = middle.Project(Eigen::Vector3d(0, 0, 1));
  EXPECT_NEAR(pixel.x(), 79.5, 10.0);
  EXPECT_NEAR(pixel.y(), 59.5, 10.0);
}

TEST(PathThroughCameras, ClosedLoopAndRescaledIntrinsics) {
  const std::vector<Camera> keys = KeyCameras();
  KeyCameraPathOptions options;
  options.num_frames = 40;
  options.closed = true;
  options.width_px = 320;
  options.height_px = 240;
  const std::vector<Camera> path = PathThroughCameras(keys, options);
  const std::vector<int> at = KeyFrameIndices(4, options);
  ASSERT_EQ(at, (std::vector<int>{0, 10, 20, 30}));
  for (int j = 0; j < 4; ++j) {
    EXPECT_EQ(path[at[j]].width, 320);
    EXPECT_NEAR(path[at[j]].K(0, 0), 2.0 * keys[j].K(0, 0), 1e-9);
    // The same world point lands on the same relative image position (twice the pixel + 0.5).
    const Eigen::Vector3d point(0.1, 0.2, 1.1);
    const Eigen::Vector2d key_pixel = keys[j].K.topLeftCorner<2, 3>() *
                                      (keys[j].PointInCamera(point) / keys[j].PointInCamera(point).z());
    EXPECT_LT((path[at[j]].Project(point) - (2.0 * (key_pixel.array() + 0.5) - 0.5).matrix()).norm(), 1e-9);
  }
  // The last frame leads back towards the first key.
  const double closing = (path.back().center_in_world() - keys[0].center_in_world()).norm();
  const double typical = (path[1].center_in_world() - path[0].center_in_world()).norm();
  EXPECT_LT(closing, 3.0 * typical);
}

TEST(PathThroughCameras, RejectsTooFewFrames) {
  KeyCameraPathOptions options;
  options.num_frames = 3;
  EXPECT_THROW(PathThroughCameras(KeyCameras(), options), UsageError);
  EXPECT_THROW(PathThroughCameras({}, options), UsageError);
}

TEST(CameraPath, FixedSortedFrozenAndAlongSequence) {
  const std::vector<Camera> keys = KeyCameras();
  const std::vector<Camera> fixed = FixedPath(keys[1], 5);
  ASSERT_EQ(fixed.size(), 5u);
  EXPECT_TRUE(fixed[4].has_distortion()) << "a fixed camera keeps its distortion";
  EXPECT_EQ(fixed[4].name, "key1");

  std::vector<Camera> shuffled = {keys[2], keys[0], keys[3], keys[1]};
  const std::vector<Camera> sorted = SortByAzimuth(shuffled, Eigen::Vector3d(0, 0, 1));
  for (int j = 0; j < 4; ++j) EXPECT_EQ(sorted[j].name, keys[j].name);

  const std::vector<PathFrame> frozen = FrozenTime(keys, 7);
  ASSERT_EQ(frozen.size(), 4u);
  for (const PathFrame& entry : frozen) EXPECT_EQ(entry.frame, 7);

  const std::vector<PathFrame> along = AlongSequence(keys, {10, 11, 12, 13, 14, 15, 16});
  ASSERT_EQ(along.size(), 7u);
  EXPECT_EQ(along.front().camera.name, "key0");
  EXPECT_EQ(along.back().camera.name, "key3");
  EXPECT_EQ(along[3].frame, 13);
  EXPECT_THROW(AlongSequence({}, {1}), UsageError);
}

}  // namespace
}  // namespace confluent
