// The studio actor performing a BVH file: retargeted bone directions on the studio skeleton.

#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "studio/actor.h"
#include "studio/motion.h"
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

}  // namespace
}  // namespace confluent
