#pragma once
// Ground truth for tracking tests: the template's own silhouettes in a known pose, and the poses.

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "silhouette/overlap.h"
#include "tracking/body_template.h"
#include "tracking/landmark_joints.h"

namespace confluent::testing {

// The template's silhouettes in `pose`, one per camera of `rig` (centre-sampled).
inline std::vector<Image> TemplateMasks(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& pose,
                                        const Rig& rig) {
  const Mesh mesh = body.PosedMesh(shape, pose);
  std::vector<Image> masks;
  for (const Camera& camera : rig.cameras) masks.push_back(RasterizeClosedMesh(mesh, camera));
  return masks;
}

// Per pixel, the union of the template's silhouettes in poses `a` and `b`: masks the silhouettes
// cannot settle between the two.
inline std::vector<Image> UnionTemplateMasks(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& a,
                                             const TemplatePose& b, const Rig& rig) {
  std::vector<Image> masks = TemplateMasks(body, shape, a, rig);
  const std::vector<Image> other = TemplateMasks(body, shape, b, rig);
  for (std::size_t c = 0; c < masks.size(); ++c)
    for (std::size_t i = 0; i < masks[c].data.size(); ++i)
      masks[c].data[i] = std::max(masks[c].data[i], other[c].data[i]);
  return masks;
}

// Where a perfect detector puts the knuckles' midpoint on the hand of `wrist` (template order,
// `joints` in the same order): 60% of the way to the hand's end.
inline Eigen::Vector3d KnucklesOf(const std::vector<Eigen::Vector3d>& joints, int wrist) {
  return joints[wrist] + 0.6 * (joints[wrist + 1] - joints[wrist]);
}

// The landmark joints a perfect detector gives for the template in `pose`: its 14 limb joints,
// and the knuckles (KnucklesOf).
inline LandmarkJoints TemplateLandmarks(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& pose) {
  LandmarkJoints landmarks;
  landmarks.position = body.JointPositions(shape, pose);
  landmarks.cameras.assign(kNumTemplateJoints, 0);
  landmarks.rms_px.assign(kNumTemplateJoints, 1.0);
  for (int j : {kJointLeftShoulder, kJointLeftElbow, kJointLeftWrist, kJointRightShoulder, kJointRightElbow,
                kJointRightWrist, kJointLeftHip, kJointLeftKnee, kJointLeftAnkle, kJointLeftToe, kJointRightHip,
                kJointRightKnee, kJointRightAnkle, kJointRightToe})
    landmarks.cameras[j] = 8;
  for (int side = 0; side < 2; ++side) {
    const int wrist = side ? kJointRightWrist : kJointLeftWrist;
    landmarks.knuckles[side] = KnucklesOf(landmarks.position, wrist);
    landmarks.knuckle_cameras[side] = 8;
  }
  return landmarks;
}

// The shoulder rotation that turns the generic upper arm from rest to `direction` (chest frame).
inline std::array<double, 3> ArmTowards(const BodyTemplate& body, int shoulder, const Eigen::Vector3d& direction) {
  const auto& rest = body.generic_rest();
  const Eigen::AngleAxisd turn(
      Eigen::Quaterniond::FromTwoVectors((rest[shoulder + 1] - rest[shoulder]).normalized(), direction.normalized()));
  const Eigen::Vector3d v = turn.angle() * turn.axis();
  return {v.x(), v.y(), v.z()};
}

// `pose` with the left arm folded down across the chest (seen inside the torso from the front).
inline TemplatePose WithLeftArmFolded(const BodyTemplate& body, TemplatePose pose) {
  pose.dofs[kJointLeftShoulder] = ArmTowards(body, kJointLeftShoulder, Eigen::Vector3d(-0.2, 0.3, -1.0));
  pose.dofs[kJointLeftElbow] = {1.9, 0, 0};
  return pose;
}

}  // namespace confluent::testing
