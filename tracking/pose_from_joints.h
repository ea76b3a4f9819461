#pragma once
// Driving the body template from a skeleton: fits a TemplatePose to world joint positions and,
// when known, world joint orientations (for example the studio's ground-truth joints.json,
// whose joints carry the template's names), with Ceres. Joint limits are respected, so the
// template follows as closely as its degrees of freedom allow.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "tracking/body_template.h"

namespace confluent {

// Options of FitPoseToJoints.
struct PoseFromJointsOptions {
  // Weight of the orientation residuals: a rotation error of 1 rad counts like a position error
  // of this many metres (per joint, on each rotated axis).
  double rotation_weight_m = 0.1;
  int max_iterations = 60;       // Levenberg-Marquardt iterations
  // Per joint (template order), how much its residuals count; 0 leaves the joint free. Empty:
  // every joint counts 1.
  std::vector<double> joint_weights;
  // Throws UsageError for out-of-range values.
  void Check() const;
};

// Fits the pose of the template with `shape` to `joints_in_world` (kNumTemplateJoints positions,
// template joint order, metres). `world_rotations` (may be null or empty) are the joints'
// accumulated world rotations relative to the rest pose (core/skeleton.h convention: the
// rotation part of WorldFromJoint); they make twists observable. Starts from `initial`.
// Throws UsageError when a vector has the wrong size.
TemplatePose FitPoseToJoints(const BodyTemplate& body, const BodyShape& shape,
                             const std::vector<Eigen::Vector3d>& joints_in_world,
                             const std::vector<Eigen::Quaterniond>* world_rotations, const TemplatePose& initial,
                             const PoseFromJointsOptions& options = {});

}  // namespace confluent
