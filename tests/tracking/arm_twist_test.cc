// Arm twist (issue 19): an arm held straight turns about its own axis unseen, and when it bends
// the tracker must find the plane it bends in. Ground truth: the template's own silhouettes in
// known poses, so every joint error is the tracker's.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

#include "tracking/limb_hypotheses.h"
#include "tracking/tracker.h"
#include "tests/support/camera_ring.h"
#include "tests/support/template_masks.h"

namespace confluent {
namespace {

constexpr double kDegree = M_PI / 180.0;

// The right upper arm reaching forward and a little out, turned `twist_deg` about itself, the
// elbow flexed `elbow_deg`.
TemplatePose RightArmForward(const BodyTemplate& body, double twist_deg, double elbow_deg) {
  TemplatePose pose;
  pose.root_rotation = Eigen::Vector3d(0, 0, 0.3);
  const auto& rest = body.generic_rest();
  const Eigen::Vector3d bone = (rest[kJointRightElbow] - rest[kJointRightShoulder]).normalized();
  const auto towards = testing::ArmTowards(body, kJointRightShoulder, Eigen::Vector3d(0.4, 1.0, 0.1));
  const Eigen::Vector3d v(towards[0], towards[1], towards[2]);
  const Eigen::AngleAxisd turned(Eigen::AngleAxisd(v.norm(), v.normalized()) * Eigen::AngleAxisd(twist_deg * kDegree, bone));
  const Eigen::Vector3d r = turned.angle() * turned.axis();
  pose.dofs[kJointRightShoulder] = {r.x(), r.y(), r.z()};
  pose.dofs[kJointRightElbow][0] = elbow_deg * kDegree;
  return pose;
}

bool HasFlag(const TrackedFrame& frame, const std::string& flag) {
  return std::find(frame.flags.begin(), frame.flags.end(), flag) != frame.flags.end();
}

TEST(ArmTwistHypotheses, TurnTheForearmAboutTheUpperArmWhoseElbowStaysPut) {
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.75);
  const TemplatePose straight = RightArmForward(body, 0.0, 2.0);
  const auto joints = body.JointPositions(shape, straight);
  const Eigen::Vector3d upper = (joints[kJointRightElbow] - joints[kJointRightShoulder]).normalized();
  const std::vector<TemplatePose> hypotheses = ArmTwistHypotheses(body, straight, Limb::kRightArm, 30.0 * kDegree);
  ASSERT_EQ(hypotheses.size(), 3u);
  std::vector<Eigen::Vector3d> bends;  // each forearm's direction across the upper arm
  for (const TemplatePose& hypothesis : hypotheses) {
    const auto turned = body.JointPositions(shape, hypothesis);
    EXPECT_LT((turned[kJointRightElbow] - joints[kJointRightElbow]).norm(), 1e-9);
    EXPECT_LT((turned[kJointLeftWrist] - joints[kJointLeftWrist]).norm(), 1e-9);  // the other arm is left alone
    EXPECT_NEAR(hypothesis.dofs[kJointRightElbow][0], 30.0 * kDegree, 1e-12);
    const Eigen::Vector3d forearm = (turned[kJointRightWrist] - turned[kJointRightElbow]).normalized();
    EXPECT_NEAR(std::acos(std::clamp(forearm.dot(upper), -1.0, 1.0)), 30.0 * kDegree, 1e-6);
    bends.push_back((forearm - forearm.dot(upper) * upper).normalized());
  }
  // Turned by 90, 180 and -90 degrees: the bends point to three sides of the upper arm.
  EXPECT_NEAR(bends[0].dot(bends[1]), 0.0, 1e-6);
  EXPECT_NEAR(bends[1].dot(bends[2]), 0.0, 1e-6);
  EXPECT_NEAR(bends[0].dot(bends[2]), -1.0, 1e-6);
  // A bent elbow is not straightened.
  EXPECT_NEAR(ArmTwistHypotheses(body, RightArmForward(body, 0.0, 60.0), Limb::kRightArm, 30.0 * kDegree)[0]
                  .dofs[kJointRightElbow][0],
              60.0 * kDegree, 1e-12);
  EXPECT_TRUE(ArmTwistHypotheses(body, straight, Limb::kRightLeg, 30.0 * kDegree).empty());
}

// The arm was held straight, turned 180 degrees from the truth (nothing in the silhouettes says
// otherwise); now it bends 35 degrees. The frame-to-frame fit bends it in the wrong plane or not
// at all; the twist search turns it and finds the bend.
TEST(ArmTwist, AStraightArmTurnedTheWrongWayIsTurnedBackWhenItBends) {
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.75);
  const Rig rig = testing::CameraRing(8, 320, 240);
  const TemplatePose held = RightArmForward(body, 180.0, 2.0);
  const TemplatePose bent = RightArmForward(body, 0.0, 35.0);
  const std::vector<Image> masks = testing::TemplateMasks(body, shape, bent, rig);
  const Eigen::Vector3d true_wrist = body.JointPositions(shape, bent)[kJointRightWrist];
  auto track = [&](bool search) {
    TrackerOptions options;
    options.limb_search = false;
    options.landmark_check_every = 0;
    options.arm_twist_search = search;
    Tracker tracker(rig, {}, options);
    tracker.Resume(shape, {held, held}, std::vector<double>(5, 0.97), {});
    return tracker.Track(10, masks);  // a multiple of arm_twist_every
  };
  const TrackedFrame without = track(false);
  const TrackedFrame with = track(true);
  const double error_without = (without.joints[kJointRightWrist] - true_wrist).norm();
  const double error_with = (with.joints[kJointRightWrist] - true_wrist).norm();
  EXPECT_GT(error_without, 0.04) << "the fit alone should not find the bend (else this test shows nothing)";
  EXPECT_LT(error_with, 0.015);
  EXPECT_TRUE(HasFlag(with, "twist:right_arm"));
  EXPECT_FALSE(HasFlag(without, "twist:right_arm"));
  EXPECT_GT(with.mean_iou, without.mean_iou + 0.002);
}

// Arms that are straight in the truth too keep their pose: no hypothesis overlaps better.
TEST(ArmTwist, AStraightArmThatIsRightIsLeftAlone) {
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.75);
  const Rig rig = testing::CameraRing(8, 320, 240);
  const TemplatePose straight = RightArmForward(body, 0.0, 2.0);
  TrackerOptions options;
  options.limb_search = false;
  options.landmark_check_every = 0;
  Tracker tracker(rig, {}, options);
  tracker.Resume(shape, {straight, straight}, std::vector<double>(5, 0.97), {});
  const TrackedFrame frame = tracker.Track(10, testing::TemplateMasks(body, shape, straight, rig));
  EXPECT_FALSE(HasFlag(frame, "twist:right_arm"));
  EXPECT_FALSE(HasFlag(frame, "twist:left_arm"));
  EXPECT_LT((frame.joints[kJointRightWrist] - body.JointPositions(shape, straight)[kJointRightWrist]).norm(), 0.015);
}

}  // namespace
}  // namespace confluent
