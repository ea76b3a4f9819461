#include "core/skeleton.h"

namespace confluent {

int Skeleton::IndexOf(const std::string& name) const {
  for (int i = 0; i < size(); ++i)
    if (joints[i].name == name) return i;
  return -1;
}

bool Skeleton::IsTopologicallyOrdered() const {
  for (int i = 0; i < size(); ++i)
    if (joints[i].parent >= i || (i > 0 && joints[i].parent < 0)) return false;
  return !joints.empty() && joints[0].parent == -1;
}

std::vector<Eigen::Vector3d> Skeleton::RestPositions() const {
  std::vector<Eigen::Vector3d> positions(joints.size());
  for (int i = 0; i < size(); ++i)
    positions[i] = (joints[i].parent < 0 ? Eigen::Vector3d::Zero() : positions[joints[i].parent]) +
                   joints[i].offset_in_parent;
  return positions;
}

Pose Pose::Rest(int num_joints) {
  Pose pose;
  pose.local_rotations.assign(num_joints, Eigen::Quaterniond::Identity());
  return pose;
}

std::vector<Eigen::Isometry3d> WorldFromJoint(const Skeleton& skeleton, const Pose& pose) {
  const int n = skeleton.size();
  std::vector<Eigen::Isometry3d> world_from_joint(n);
  std::vector<Eigen::Quaterniond> world_rotation(n);
  std::vector<Eigen::Vector3d> position(n);
  for (int i = 0; i < n; ++i) {
    const Joint& joint = skeleton.joints[i];
    const Eigen::Quaterniond& local =
        i < static_cast<int>(pose.local_rotations.size()) ? pose.local_rotations[i] : Eigen::Quaterniond::Identity();
    if (joint.parent < 0) {
      world_rotation[i] = local.normalized();
      position[i] = joint.offset_in_parent + pose.root_translation;
    } else {
      world_rotation[i] = (world_rotation[joint.parent] * local).normalized();
      position[i] = position[joint.parent] + world_rotation[joint.parent] * joint.offset_in_parent;
    }
    world_from_joint[i] = Eigen::Isometry3d::Identity();
    world_from_joint[i].linear() = world_rotation[i].toRotationMatrix();
    world_from_joint[i].translation() = position[i];
  }
  return world_from_joint;
}

std::vector<Eigen::Vector3d> JointPositions(const Skeleton& skeleton, const Pose& pose) {
  std::vector<Eigen::Vector3d> positions;
  for (const auto& transform : WorldFromJoint(skeleton, pose)) positions.push_back(transform.translation());
  return positions;
}

}  // namespace confluent
