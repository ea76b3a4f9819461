// The studio actor performing a BVH file: retargeted bone directions on the studio skeleton.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "core/error.h"
#include "studio/actor.h"
#include "studio/motion.h"
#include "studio/rig.h"
#include "tests/support/bvh_fixture.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using namespace testing::bvh_fixture;  // NOLINT

Vector3d Bone(const Skeleton& skeleton, const Pose& pose, const char* from, const char* to) {
  const auto p = JointPositions(skeleton, pose);
  return (p[skeleton.IndexOf(to)] - p[skeleton.IndexOf(from)]).normalized();
}

TEST(StudioBvh, ActorBonesFollowTheBvh) {
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(TestFrames());
  const Skeleton skeleton = MakeStudioSkeleton();
  StudioMotionOptions options;
  options.fps = 50.0;  // the BVH's own rate: 3 frames
  options.bvh_path = dir / "m.bvh";
  const std::vector<Pose> poses = StudioPerformance(skeleton, options);
  ASSERT_EQ(poses.size(), 3u);
  // Frame 0, the BVH's T-pose: the actor (facing +y, its left at -x) holds its arms out.
  EXPECT_GT(Bone(skeleton, poses[0], "left_shoulder", "left_elbow").dot(Vector3d(-1, 0, 0)), 1 - 1e-9);
  EXPECT_GT(Bone(skeleton, poses[0], "right_elbow", "right_wrist").dot(Vector3d(1, 0, 0)), 1 - 1e-9);
  // Frame 1: left upper arm down, forearm forwards, left thigh 45 degrees forwards.
  EXPECT_GT(Bone(skeleton, poses[1], "left_shoulder", "left_elbow").dot(Vector3d(0, 0, -1)), 1 - 1e-9);
  EXPECT_GT(Bone(skeleton, poses[1], "left_elbow", "left_wrist").dot(Vector3d(0, 1, 0)), 1 - 1e-9);
  EXPECT_GT(Bone(skeleton, poses[1], "left_hip", "left_knee").dot(Vector3d(0, 1, -1).normalized()), 1 - 1e-9);
  // Sampling at a quarter of the BVH rate interpolates between BVH frames: 2 frames over 0.04 s.
  options.fps = 25.0;
  EXPECT_EQ(BvhPerformance(skeleton, options).size(), 2u);
  options.num_frames = 1;
  EXPECT_EQ(BvhPerformance(skeleton, options).size(), 1u);
  // A missing file is an InputError naming it.
  options.bvh_path = dir / "missing.bvh";
  EXPECT_THROW(StudioPerformance(skeleton, options), InputError);
}

// A performance that walks 3 m in 4 s (at 25 fps) while swaying 4 cm from side to side at 2 Hz.
std::vector<Pose> WalkingPerformance(const Skeleton& skeleton, std::vector<double>* sway) {
  std::vector<Pose> poses;
  for (int f = 0; f < 100; ++f) {
    const double t = f / 25.0;
    Pose pose = Pose::Rest(skeleton.size());
    sway->push_back(0.04 * std::sin(2 * M_PI * 2 * t));
    pose.root_translation = Vector3d(5.0 + (*sway)[f], 0.75 * t, 0.0);
    poses.push_back(pose);
  }
  return poses;
}

TEST(StudioBvh, TravellingPerformanceIsCentredPerformedOnTheSpotOrRefused) {
  const Skeleton skeleton = MakeStudioSkeleton();
  std::vector<double> sway;
  const std::vector<Pose> walk = WalkingPerformance(skeleton, &sway);
  const Eigen::Vector2d centre(0.2, -0.1);
  const Vector3d pelvis_rest = skeleton.joints[0].offset_in_parent;
  // Too far for a 1 m volume: refused, naming the file and the way out.
  std::vector<Pose> poses = walk;
  try {
    KeepPerformanceInVolume(&poses, skeleton, centre, 1.0, 25.0, false, "walk.bvh");
    ADD_FAILURE() << "a 3 m walk was accepted in a 1 m volume";
  } catch (const InputError& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("walk.bvh"), std::string::npos) << what;
    EXPECT_NE(what.find("--bvh-in-place"), std::string::npos) << what;
  }
  // A 2 m volume holds it, centred: the path's ends are half the walk either side of the centre.
  poses = walk;
  const PerformancePlacement centred = KeepPerformanceInVolume(&poses, skeleton, centre, 2.0, 25.0, false, "walk.bvh");
  const double half_walk = 0.5 * 0.75 * 99 / 25.0;
  EXPECT_NEAR(centred.travel_m, half_walk, 0.01);
  EXPECT_NEAR((pelvis_rest + poses.front().root_translation).y(), centre.y() - half_walk, 1e-9);
  EXPECT_NEAR((pelvis_rest + poses.back().root_translation).y(), centre.y() + half_walk, 1e-9);
  EXPECT_NEAR((poses[50].root_translation - walk[50].root_translation).x(), centre.x() - 5.0, 1e-9);
  // On the spot: the walk is gone, the sway is kept (to 10% half a second from the ends, where
  // the sliding mean sees all of its window; to 60% at the ends).
  poses = walk;
  const PerformancePlacement on_the_spot = KeepPerformanceInVolume(&poses, skeleton, centre, 0.1, 25.0, true, "walk.bvh");
  EXPECT_TRUE(on_the_spot.made_in_place);
  EXPECT_LT(on_the_spot.radius_m, 0.1);
  double forward = 0.0, sway_error_inside = 0.0, sway_error = 0.0;
  const double shift = (pelvis_rest + poses[50].root_translation).x() - centre.x() - sway[50];
  for (std::size_t f = 0; f < poses.size(); ++f) {
    const Vector3d at = pelvis_rest + poses[f].root_translation;
    forward = std::max(forward, std::abs(at.y() - centre.y()));
    const double error = std::abs(at.x() - centre.x() - shift - sway[f]);
    sway_error = std::max(sway_error, error);
    if (f >= 13 && f + 13 < poses.size()) sway_error_inside = std::max(sway_error_inside, error);
  }
  EXPECT_LT(forward, 0.02);
  EXPECT_LT(sway_error_inside, 0.1 * 0.04);
  EXPECT_LT(sway_error, 0.6 * 0.04);
}

TEST(StudioBvh, CaptureVolumeGrowsWithTheRingAndShrinksWithThePerformer) {
  StudioRigOptions rig;
  const double standard = CaptureVolumeRadius(MakeStudioRig(rig), rig.num_ring_cameras, rig.target_in_world, 1.75);
  EXPECT_GT(standard, 0.2);
  EXPECT_LT(standard, rig.ring_radius_m);
  EXPECT_LT(CaptureVolumeRadius(MakeStudioRig(rig), rig.num_ring_cameras, rig.target_in_world, 2.0), standard);
  EXPECT_EQ(CaptureVolumeRadius(MakeStudioRig(rig), rig.num_ring_cameras, rig.target_in_world, 4.0), 0.0);
  rig.ring_radius_m = 6.0;
  EXPECT_GT(CaptureVolumeRadius(MakeStudioRig(rig), rig.num_ring_cameras, rig.target_in_world, 1.75), standard + 0.5);
}

}  // namespace
}  // namespace confluent
