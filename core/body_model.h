#pragma once
// The 22-joint human body that the synthetic actor (studio/), the tracking template (tracking/)
// and BVH retargeting (core/bvh_retarget.h) share: joint names, parents and the generic rest
// pose. The 16 segments it carries are in core/body_segments.h.
//
// Frame and units: world Z up, metres. At rest the body stands at the origin in an A-pose,
// facing +y; its left side is -x.

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace confluent {

enum BodyJoint {
  kJointPelvis, kJointSpine, kJointChest, kJointNeck, kJointHead, kJointHeadEnd,
  kJointLeftShoulder, kJointLeftElbow, kJointLeftWrist, kJointLeftHandEnd,
  kJointRightShoulder, kJointRightElbow, kJointRightWrist, kJointRightHandEnd,
  kJointLeftHip, kJointLeftKnee, kJointLeftAnkle, kJointLeftToe,
  kJointRightHip, kJointRightKnee, kJointRightAnkle, kJointRightToe,
};
constexpr int kNumBodyJoints = 22;

// "pelvis", "spine", ..., "right_toe", in BodyJoint order.
const std::vector<std::string>& BodyJointNames();

// Each joint's parent (-1 for the pelvis, the root).
const std::array<int, kNumBodyJoints>& BodyJointParents();

// Whether two of the body's 16 surface segments meet at `joint` (the spine between the lower and
// the upper torso, the neck, the head, the shoulders, elbows, wrists, hips, knees and ankles).
// Not the pelvis, the root, inside the lower torso; not the chest, inside the upper torso; not the
// ends of the head, hands and feet.
bool JointJoinsSegments(int joint);

// Rest joint positions of a 1.75 m adult, the upper arms `arm_angle_rad` from the vertical.
std::array<Eigen::Vector3d, kNumBodyJoints> BodyRestPositions(double arm_angle_rad);

}  // namespace confluent
