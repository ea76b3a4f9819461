#pragma once
// Ground truth for tracking tests: the template's own silhouettes in a known pose, and the poses.

#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "silhouette/overlap.h"
#include "tracking/body_template.h"

namespace confluent::testing {

// The template's silhouettes in `pose`, one per camera of `rig` (centre-sampled).
inline std::vector<Image> TemplateMasks(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& pose,
                                        const Rig& rig) {
  const Mesh mesh = body.PosedMesh(shape, pose);
  std::vector<Image> masks;
  for (const Camera& camera : rig.cameras) masks.push_back(RasterizeClosedMesh(mesh, camera));
  return masks;
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
