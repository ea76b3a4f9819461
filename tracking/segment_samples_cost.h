#pragma once
// INTERNAL (tracking/*.cc and their tests): the model -> image term of the silhouette fit for a
// segment whose shape is held fixed (every tracked frame), with its Jacobian by hand. Each
// surface sample of the segment is moved by the pose, projected, and its residual is the
// silhouette's signed distance there when positive (outside), else 0. The pose enters only
// through the segment's world transform, so that transform's derivatives are taken once per
// evaluation (Jets) and each sample costs a few dozen multiplications; a sample inside the
// silhouette costs none. The automatic-differentiation functor it replaces evaluated every
// sample in 18-wide Jets.

#include <ceres/cubic_interpolation.h>
#include <ceres/dynamic_cost_function.h>

#include <Eigen/Core>
#include <array>
#include <vector>

#include "calib/camera.h"
#include "tracking/body_template.h"

namespace confluent::tracking_internal {

using SignedDistanceInterpolator = ceres::BiCubicInterpolator<ceres::Grid2D<float, 1>>;

// Parameter blocks, in order: root translation (3), root rotation vector (3), the DOF blocks of
// `chain_joints` (the joints with DOFs from the root to the segment's joint), then any further
// blocks the caller adds (the shape block), on which the residuals do not depend.
class SegmentSamplesCost : public ceres::DynamicCostFunction {
 public:
  // `local_samples`: the samples relative to the segment's joint, in the rest frame whose joint
  // positions are `rest`. `distance` is sampled in reduced pixels: pixel p of the camera is at
  // (p + 0.5) / `scale` - 0.5. Throws std::invalid_argument when the chain has more than
  // kMaxPoseParameters pose parameters.
  SegmentSamplesCost(const BodyTemplate& body, int joint, std::vector<int> chain_joints,
                     const Eigen::Matrix3d& root_reference, const std::array<Eigen::Vector3d, kNumTemplateJoints>& rest,
                     std::vector<Eigen::Vector3d> local_samples, const Camera& camera, double scale,
                     const SignedDistanceInterpolator& distance);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

  static constexpr int kMaxPoseParameters = 24;

 private:
  const BodyTemplate& body_;
  int joint_;
  std::vector<int> chain_joints_;
  Eigen::Matrix3d root_reference_;
  std::array<Eigen::Vector3d, kNumTemplateJoints> rest_;
  std::vector<Eigen::Vector3d> local_samples_;
  Camera camera_;
  double scale_;
  const SignedDistanceInterpolator& distance_;
  int num_pose_parameters_ = 6;
};

}  // namespace confluent::tracking_internal
