// Pose from joints: FitPoseToJoints drives the body template from world joint positions (and,
// when known, orientations) with a Ceres fit; the cost functor lives only in this translation unit.

#include <ceres/ceres.h>

#include <algorithm>

#include "core/error.h"
#include "tracking/body_model_impl.h"
#include "tracking/pose_from_joints.h"

namespace confluent {

namespace ti = tracking_internal;
using Eigen::Matrix3d;
using Eigen::Vector3d;

void PoseFromJointsOptions::Check() const {
  RequireOption(rotation_weight_m >= 0, "PoseFromJointsOptions.rotation_weight_m", rotation_weight_m, ">= 0");
  RequireOption(max_iterations >= 1, "PoseFromJointsOptions.max_iterations", max_iterations, ">= 1");
  RequireOption(joint_weights.empty() || static_cast<int>(joint_weights.size()) == kNumTemplateJoints,
                "PoseFromJointsOptions.joint_weights", static_cast<double>(joint_weights.size()),
                "empty or one per template joint (" + std::to_string(kNumTemplateJoints) + ")");
  for (double w : joint_weights) RequireOption(w >= 0, "PoseFromJointsOptions.joint_weights", w, ">= 0");
}

namespace {

// Residuals of one joint: its world position against the target (3) and, optionally, its world
// rotation against the target rotation (9, scaled by rotation_weight). Parameter blocks: root
// translation, root rotation vector, then the DOF blocks of the chain.
struct JointCost {
  const BodyTemplate* body = nullptr;
  int joint = 0;
  std::array<Vector3d, kNumTemplateJoints> rest;
  std::vector<int> chain_joints;
  Vector3d target = Vector3d::Zero();
  bool has_rotation = false;
  Matrix3d target_rotation = Matrix3d::Identity();
  double rotation_weight = 0.1;

  template <typename T>
  bool operator()(T const* const* p, T* residuals) const {
    const T* jp[kNumTemplateJoints] = {};
    for (std::size_t i = 0; i < chain_joints.size(); ++i) jp[chain_joints[i]] = p[2 + i];
    std::array<ti::Vec3<T>, kNumTemplateJoints> rest_t;
    for (int j = 0; j < kNumTemplateJoints; ++j) rest_t[j] = rest[j].cast<T>();
    ti::Mat3<T> R;
    ti::Vec3<T> P;
    ti::JointWorldTransform(*body, joint, rest_t, p[0], p[1], Matrix3d::Identity(), jp, &R, &P);
    for (int k = 0; k < 3; ++k) residuals[k] = P[k] - T(target[k]);
    if (has_rotation)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) residuals[3 + 3 * r + c] = T(rotation_weight) * (R(r, c) - T(target_rotation(r, c)));
    return true;
  }
};

}  // namespace

TemplatePose FitPoseToJoints(const BodyTemplate& body, const BodyShape& shape, const std::vector<Vector3d>& joints_in_world,
                             const std::vector<Eigen::Quaterniond>* world_rotations, const TemplatePose& initial,
                             const PoseFromJointsOptions& options) {
  options.Check();
  if (static_cast<int>(joints_in_world.size()) != kNumTemplateJoints)
    throw UsageError("FitPoseToJoints: expected " + std::to_string(kNumTemplateJoints) + " joint positions");
  const bool rotations = world_rotations && !world_rotations->empty();
  if (rotations && static_cast<int>(world_rotations->size()) != kNumTemplateJoints)
    throw UsageError("FitPoseToJoints: expected " + std::to_string(kNumTemplateJoints) + " joint rotations");
  TemplatePose pose = initial;
  body.ClampToLimits(&pose);
  double root_t[3] = {pose.root_translation.x(), pose.root_translation.y(), pose.root_translation.z()};
  double root_aa[3] = {pose.root_rotation.x(), pose.root_rotation.y(), pose.root_rotation.z()};
  const auto rest = body.RestPositions(shape);
  ceres::Problem problem;
  for (int j = 0; j < kNumTemplateJoints; ++j) {
    const double weight = options.joint_weights.empty() ? 1.0 : options.joint_weights[j];
    if (weight <= 0) continue;
    auto* functor = new JointCost;
    functor->body = &body;
    functor->joint = j;
    functor->rest = rest;
    for (int k = j; k > 0; k = body.parents()[k])
      if (body.dofs()[k].type != JointType::kFixed) functor->chain_joints.push_back(k);
    std::reverse(functor->chain_joints.begin(), functor->chain_joints.end());
    functor->target = joints_in_world[j];
    // A joint's rotation moves its children; end sites (no children) carry no rotation of their own.
    bool has_children = false;
    for (int c = 0; c < kNumTemplateJoints; ++c) has_children = has_children || body.parents()[c] == j;
    functor->has_rotation = rotations && has_children;
    if (functor->has_rotation) functor->target_rotation = (*world_rotations)[j].normalized().toRotationMatrix();
    functor->rotation_weight = options.rotation_weight_m;
    auto* cost = new ceres::DynamicAutoDiffCostFunction<JointCost, 16>(functor);
    std::vector<double*> blocks = {root_t, root_aa};
    cost->AddParameterBlock(3);
    cost->AddParameterBlock(3);
    for (int k : functor->chain_joints) {
      cost->AddParameterBlock(body.dofs()[k].num_dof());
      blocks.push_back(pose.dofs[k].data());
    }
    cost->SetNumResiduals(functor->has_rotation ? 12 : 3);
    problem.AddResidualBlock(cost, weight == 1.0 ? nullptr : new ceres::ScaledLoss(nullptr, weight, ceres::TAKE_OWNERSHIP),
                             blocks);
  }
  for (int j = 1; j < kNumTemplateJoints; ++j) {
    const int n = body.dofs()[j].num_dof();
    double* block = pose.dofs[j].data();
    if (n == 0 || !problem.HasParameterBlock(block)) continue;
    for (int k = 0; k < n; ++k) {
      problem.SetParameterLowerBound(block, k, body.dofs()[j].lower[k]);
      problem.SetParameterUpperBound(block, k, body.dofs()[j].upper[k]);
    }
  }
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.logging_type = ceres::SILENT;
  solver_options.function_tolerance = 1e-10;
  solver_options.parameter_tolerance = 1e-10;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  pose.root_translation = Vector3d(root_t[0], root_t[1], root_t[2]);
  pose.root_rotation = Vector3d(root_aa[0], root_aa[1], root_aa[2]);
  return pose;
}

}  // namespace confluent
