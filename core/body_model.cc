#include "core/body_model.h"

#include <cmath>

namespace confluent {

const std::vector<std::string>& BodyJointNames() {
  static const std::vector<std::string> names = {"pelvis", "spine", "chest", "neck", "head", "head_end",
                                                 "left_shoulder", "left_elbow", "left_wrist", "left_hand_end",
                                                 "right_shoulder", "right_elbow", "right_wrist", "right_hand_end",
                                                 "left_hip", "left_knee", "left_ankle", "left_toe",
                                                 "right_hip", "right_knee", "right_ankle", "right_toe"};
  return names;
}

const std::array<int, kNumBodyJoints>& BodyJointParents() {
  static const std::array<int, kNumBodyJoints> parents = {
      -1, kJointPelvis, kJointSpine, kJointChest, kJointNeck, kJointHead,
      kJointChest, kJointLeftShoulder, kJointLeftElbow, kJointLeftWrist,
      kJointChest, kJointRightShoulder, kJointRightElbow, kJointRightWrist,
      kJointPelvis, kJointLeftHip, kJointLeftKnee, kJointLeftAnkle,
      kJointPelvis, kJointRightHip, kJointRightKnee, kJointRightAnkle};
  return parents;
}

bool JointJoinsSegments(int joint) {
  switch (joint) {
    case kJointPelvis:
    case kJointChest:
    case kJointHeadEnd:
    case kJointLeftHandEnd:
    case kJointRightHandEnd:
    case kJointLeftToe:
    case kJointRightToe: return false;
    default: return joint >= 0 && joint < kNumBodyJoints;
  }
}

std::array<Eigen::Vector3d, kNumBodyJoints> BodyRestPositions(double arm_angle_rad) {
  using Eigen::Vector3d;
  std::array<Vector3d, kNumBodyJoints> r;
  r[kJointPelvis] = Vector3d(0, 0, 0.96);
  r[kJointSpine] = Vector3d(0, -0.005, 1.10);
  r[kJointChest] = Vector3d(0, -0.01, 1.28);
  r[kJointNeck] = Vector3d(0, -0.012, 1.455);
  r[kJointHead] = Vector3d(0, -0.005, 1.56);
  r[kJointHeadEnd] = Vector3d(0, 0.005, 1.75);
  for (int side = 0; side < 2; ++side) {
    const double sx = side == 0 ? -1.0 : 1.0;  // the body's left is -x
    const int shoulder = side == 0 ? kJointLeftShoulder : kJointRightShoulder;
    const Vector3d dir(sx * std::sin(arm_angle_rad), 0.0, -std::cos(arm_angle_rad));
    r[shoulder] = Vector3d(sx * 0.19, -0.015, 1.425);
    r[shoulder + 1] = r[shoulder] + 0.285 * dir;
    r[shoulder + 2] = r[shoulder + 1] + 0.25 * dir;
    r[shoulder + 3] = r[shoulder + 2] + 0.18 * dir;
    const int hip = side == 0 ? kJointLeftHip : kJointRightHip;
    r[hip] = Vector3d(sx * 0.09, 0.0, 0.91);
    r[hip + 1] = Vector3d(sx * 0.102, 0.005, 0.49);
    r[hip + 2] = Vector3d(sx * 0.112, -0.02, 0.085);
    r[hip + 3] = Vector3d(sx * 0.125, 0.15, 0.02);
  }
  return r;
}

}  // namespace confluent
