#pragma once
// Kinematic skeletons and poses, shared by BVH I/O, the studio actor and the tracker.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace confluent {

// One joint. The rest pose has identity local rotations; a joint's rest position is its
// parent's rest position plus `offset_in_parent` (metres, world-aligned axes at rest).
struct Joint {
  std::string name;
  int parent = -1;  // index into Skeleton::joints, -1 for the root; parents precede children
  Eigen::Vector3d offset_in_parent = Eigen::Vector3d::Zero();
};

// A tree of joints in topological order (joint 0 is the root).
struct Skeleton {
  std::vector<Joint> joints;

  int size() const { return static_cast<int>(joints.size()); }
  // Index of the joint called `name`, or -1.
  int IndexOf(const std::string& name) const;
  // Rest-pose joint positions (root at the origin plus its offset), n x 3.
  std::vector<Eigen::Vector3d> RestPositions() const;
  // True when joint 0 is the only root and every parent precedes its children.
  bool IsTopologicallyOrdered() const;
};

// A pose: root translation plus each joint's rotation relative to its parent's frame.
struct Pose {
  Eigen::Vector3d root_translation = Eigen::Vector3d::Zero();  // added to the root position, m
  std::vector<Eigen::Quaterniond> local_rotations;             // one per joint

  // The rest pose of a skeleton with `num_joints` joints.
  static Pose Rest(int num_joints);
};

// Forward kinematics: world_from_joint transforms (rotation = accumulated rotation, translation
// = joint position in the world). A point p at rest maps to T[j] * (p - rest_position[j]).
std::vector<Eigen::Isometry3d> WorldFromJoint(const Skeleton& skeleton, const Pose& pose);

// World positions of all joints in `pose`.
std::vector<Eigen::Vector3d> JointPositions(const Skeleton& skeleton, const Pose& pose);

}  // namespace confluent
