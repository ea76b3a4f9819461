#include "core/body_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace confluent {
namespace {

TEST(BodyModel, JointsFormOneTreeRootedAtThePelvis) {
  const std::vector<std::string>& names = BodyJointNames();
  ASSERT_EQ(names.size(), static_cast<std::size_t>(kNumBodyJoints));
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
  EXPECT_EQ(names[kJointPelvis], "pelvis");
  EXPECT_EQ(names[kJointLeftElbow], "left_elbow");
  EXPECT_EQ(names[kJointRightToe], "right_toe");
  const auto& parents = BodyJointParents();
  EXPECT_EQ(parents[kJointPelvis], -1);
  for (int j = 1; j < kNumBodyJoints; ++j) {
    EXPECT_GE(parents[j], 0) << names[j];
    EXPECT_LT(parents[j], j) << names[j] << ": parents come first";
  }
  EXPECT_EQ(parents[kJointLeftShoulder], kJointChest);
  EXPECT_EQ(parents[kJointRightHip], kJointPelvis);
}

// The A-pose: left and right mirror each other in x, the upper arm makes the given angle with
// the vertical, and the head's top is at 1.75 m.
TEST(BodyModel, RestPoseIsAMirroredAPose) {
  const double angle = 30.0 * M_PI / 180.0;
  const auto rest = BodyRestPositions(angle);
  EXPECT_DOUBLE_EQ(rest[kJointHeadEnd].z(), 1.75);
  for (int k = 0; k < 4; ++k) {
    for (int side : {kJointLeftShoulder, kJointLeftHip}) {
      const int left = side + k, right = left + (kJointRightShoulder - kJointLeftShoulder);
      const int right_leg = left + (kJointRightHip - kJointLeftHip);
      const int other = side == kJointLeftShoulder ? right : right_leg;
      EXPECT_NEAR(rest[left].x(), -rest[other].x(), 1e-12) << BodyJointNames()[left];
      EXPECT_LT(rest[left].x(), 0.0) << BodyJointNames()[left] << ": the body's left is -x";
      EXPECT_NEAR(rest[left].y(), rest[other].y(), 1e-12);
      EXPECT_NEAR(rest[left].z(), rest[other].z(), 1e-12);
    }
  }
  const Eigen::Vector3d upper_arm = rest[kJointLeftElbow] - rest[kJointLeftShoulder];
  EXPECT_NEAR(std::acos(-upper_arm.normalized().z()), angle, 1e-12);
}

}  // namespace
}  // namespace confluent
