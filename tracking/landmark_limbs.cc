#include "tracking/landmark_limbs.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tracking/pose_from_joints.h"

namespace confluent {

using Eigen::Vector3d;

double LimbDisagreement(const std::vector<Vector3d>& joints, const LandmarkJoints& landmarks, Limb limb) {
  const int end = LimbJoints(limb).end;
  return landmarks.known(end) ? (joints[end] - landmarks.position[end]).norm() : -1.0;
}

bool SkirtHidesAnkle(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& pose, Limb limb) {
  if (IsArm(limb) || shape.skirt_length_m <= 0) return false;
  const Mesh posed = body.PosedMesh(shape, pose);
  double hem_z = std::numeric_limits<double>::infinity();
  for (int f = 0; f < posed.num_faces(); ++f)
    if (posed.face_labels[f] == static_cast<int>(BodySegment::kLowerTorso))
      for (int k = 0; k < 3; ++k) hem_z = std::min(hem_z, posed.vertices(posed.faces(f, k), 2));
  return hem_z < body.JointPositions(shape, pose)[LimbJoints(limb).end].z();
}

std::vector<TemplatePose> LimbsFromLandmarks(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& pose,
                                             Limb limb, const LandmarkJoints& landmarks) {
  const LimbChain chain = LimbJoints(limb);
  if (!landmarks.known(chain.end)) return {};
  const std::vector<Vector3d> joints = body.JointPositions(shape, pose);
  const double upper = (joints[chain.middle] - joints[chain.root]).norm();
  const double lower = (joints[chain.end] - joints[chain.middle]).norm();
  // Every other joint holds its place, except the hand's or foot's end, which follows the limb.
  PoseFromJointsOptions options;
  options.joint_weights.assign(kNumTemplateJoints, 1.0);
  options.joint_weights[chain.end + 1] = 0.0;  // the hand end or the toe
  auto turned = [&](const Vector3d& middle) {
    std::vector<Vector3d> targets = joints;
    targets[chain.middle] = middle;
    targets[chain.end] = middle + lower * (landmarks.position[chain.end] - middle).normalized();
    return FitPoseToJoints(body, shape, targets, nullptr, pose, options);
  };
  std::vector<TemplatePose> out = {turned(joints[chain.middle])};
  if (landmarks.known(chain.middle)) {
    const Vector3d from = landmarks.known(chain.root) ? landmarks.position[chain.root] : joints[chain.root];
    out.push_back(turned(joints[chain.root] + upper * (landmarks.position[chain.middle] - from).normalized()));
  }
  return out;
}

namespace {

// The landmarks' hand direction (unit) for `arm`, from their wrist to their knuckles; zero when
// unknown or unreliable (HandDisagreementRad).
Vector3d LandmarkHandDirection(const std::vector<Vector3d>& joints, const LandmarkJoints& landmarks, Limb arm,
                               double max_wrist_gap_m) {
  const int hand = arm == Limb::kLeftArm ? 0 : 1;
  const int wrist = LimbJoints(arm).end;
  if (!IsArm(arm) || landmarks.knuckle_cameras[hand] <= 0 || !landmarks.known(wrist) ||
      (landmarks.position[wrist] - joints[wrist]).norm() > max_wrist_gap_m)
    return Vector3d::Zero();
  const Vector3d d = landmarks.knuckles[hand] - landmarks.position[wrist];
  constexpr double kMinHandM = 0.03;  // closer knuckles give no direction
  return d.norm() < kMinHandM ? Vector3d::Zero() : Vector3d(d.normalized());
}

}  // namespace

double HandDisagreementRad(const std::vector<Vector3d>& joints, const LandmarkJoints& landmarks, Limb arm,
                           double max_wrist_gap_m) {
  const Vector3d seen = LandmarkHandDirection(joints, landmarks, arm, max_wrist_gap_m);
  if (seen.isZero()) return -1.0;
  const int wrist = LimbJoints(arm).end;
  const Vector3d hand = (joints[wrist + 1] - joints[wrist]).normalized();
  return std::acos(std::clamp(hand.dot(seen), -1.0, 1.0));
}

std::optional<TemplatePose> HandFromLandmarks(const BodyTemplate& body, const BodyShape& shape,
                                              const TemplatePose& pose, Limb arm, const LandmarkJoints& landmarks,
                                              double max_wrist_gap_m) {
  const std::vector<Vector3d> joints = body.JointPositions(shape, pose);
  const Vector3d seen = LandmarkHandDirection(joints, landmarks, arm, max_wrist_gap_m);
  if (seen.isZero()) return std::nullopt;
  const int wrist = LimbJoints(arm).end;
  std::vector<Vector3d> targets = joints;
  targets[wrist + 1] = joints[wrist] + (joints[wrist + 1] - joints[wrist]).norm() * seen;
  return FitPoseToJoints(body, shape, targets, nullptr, pose);
}

}  // namespace confluent
