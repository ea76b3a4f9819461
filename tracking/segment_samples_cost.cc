#include "tracking/segment_samples_cost.h"

#include <ceres/jet.h>

#include <stdexcept>
#include <string>

#include "tracking/body_model_impl.h"

namespace confluent::tracking_internal {

using Eigen::Matrix3d;
using Eigen::Vector3d;

SegmentSamplesCost::SegmentSamplesCost(const BodyTemplate& body, int joint, std::vector<int> chain_joints,
                                       const Matrix3d& root_reference,
                                       const std::array<Vector3d, kNumTemplateJoints>& rest,
                                       std::vector<Vector3d> local_samples, const Camera& camera, double scale,
                                       const SignedDistanceInterpolator& distance)
    : body_(body),
      joint_(joint),
      chain_joints_(std::move(chain_joints)),
      root_reference_(root_reference),
      rest_(rest),
      local_samples_(std::move(local_samples)),
      camera_(camera),
      scale_(scale),
      distance_(distance) {
  AddParameterBlock(3);
  AddParameterBlock(3);
  for (int j : chain_joints_) {
    AddParameterBlock(body.dofs()[j].num_dof());
    num_pose_parameters_ += body.dofs()[j].num_dof();
  }
  if (num_pose_parameters_ > kMaxPoseParameters)
    throw std::invalid_argument("SegmentSamplesCost: " + std::to_string(num_pose_parameters_) +
                                " pose parameters, at most " + std::to_string(kMaxPoseParameters));
  SetNumResiduals(static_cast<int>(local_samples_.size()));
}

namespace {

// d(distorted normalised point) / d(normalised point) for OpenCV's k1 k2 p1 p2 k3 model.
Eigen::Matrix2d DistortionJacobian(const Camera& camera, double x, double y) {
  const double k1 = camera.dist(0), k2 = camera.dist(1), p1 = camera.dist(2), p2 = camera.dist(3), k3 = camera.dist(4);
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);  // d radial / d r2
  Eigen::Matrix2d J;
  J(0, 0) = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
  J(0, 1) = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
  J(1, 0) = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
  J(1, 1) = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
  return J;
}

}  // namespace

bool SegmentSamplesCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const int num_blocks = static_cast<int>(parameter_block_sizes().size());
  bool want_jacobian = false;
  for (int b = 0; b < num_blocks && jacobians; ++b) want_jacobian |= jacobians[b] != nullptr;

  // camera_from_segment: Xc = M * local + c, and its derivatives by the pose parameters
  // (rows: M row-major, then c; columns: root translation, root rotation, chain DOFs).
  Matrix3d M;
  Vector3d c;
  Eigen::Matrix<double, 12, Eigen::Dynamic> dMc(12, num_pose_parameters_);
  if (!want_jacobian) {
    const double* joint_params[kNumTemplateJoints] = {};
    for (std::size_t i = 0; i < chain_joints_.size(); ++i) joint_params[chain_joints_[i]] = parameters[2 + i];
    Mat3<double> R;
    Vec3<double> P;
    JointWorldTransform(body_, joint_, rest_, parameters[0], parameters[1], root_reference_, joint_params, &R, &P);
    M = camera_.rotation * R;
    c = camera_.rotation * P + camera_.translation;
  } else {
    using Jet = ceres::Jet<double, kMaxPoseParameters>;
    Jet root_t[3], root_aa[3], dofs[kNumTemplateJoints][3];
    int slot = 0;
    for (int k = 0; k < 3; ++k) root_t[k] = Jet(parameters[0][k], slot++);
    for (int k = 0; k < 3; ++k) root_aa[k] = Jet(parameters[1][k], slot++);
    const Jet* joint_params[kNumTemplateJoints] = {};
    for (std::size_t i = 0; i < chain_joints_.size(); ++i) {
      const int j = chain_joints_[i];
      for (int k = 0; k < body_.dofs()[j].num_dof(); ++k) dofs[j][k] = Jet(parameters[2 + i][k], slot++);
      joint_params[j] = dofs[j];
    }
    std::array<Vec3<Jet>, kNumTemplateJoints> rest;
    for (int j = 0; j < kNumTemplateJoints; ++j) rest[j] = rest_[j].cast<Jet>();
    Mat3<Jet> R;
    Vec3<Jet> P;
    JointWorldTransform(body_, joint_, rest, root_t, root_aa, root_reference_, joint_params, &R, &P);
    const Mat3<Jet> MJ = camera_.rotation.cast<Jet>() * R;
    const Vec3<Jet> cJ = camera_.rotation.cast<Jet>() * P + camera_.translation.cast<Jet>();
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) {
        M(r, k) = MJ(r, k).a;
        dMc.row(3 * r + k) = MJ(r, k).v.head(num_pose_parameters_).transpose();
      }
      c(r) = cJ(r).a;
      dMc.row(9 + r) = cJ(r).v.head(num_pose_parameters_).transpose();
    }
  }

  const Matrix3d& K = camera_.K;
  const double inv_scale = 1.0 / scale_;
  const bool distorted = camera_.has_distortion();
  Eigen::RowVectorXd row(num_pose_parameters_);
  Eigen::Matrix<double, 1, 12> coefficients;
  for (std::size_t i = 0; i < local_samples_.size(); ++i) {
    const Vector3d& local = local_samples_[i];
    const Vector3d Xc = M * local + c;
    double residual = 0.0;
    bool moving = false;  // the residual depends on the pose here
    Eigen::Vector3d gradient = Eigen::Vector3d::Zero();  // d residual / d Xc
    if (Xc.z() >= 1e-3) {
      const double x = Xc.x() / Xc.z(), y = Xc.y() / Xc.z();
      const Eigen::Vector2d xd = distorted ? camera_.Distort(Eigen::Vector2d(x, y)) : Eigen::Vector2d(x, y);
      const double us = (K(0, 0) * xd.x() + K(0, 1) * xd.y() + K(0, 2) + 0.5) * inv_scale - 0.5;
      const double vs = (K(1, 1) * xd.y() + K(1, 2) + 0.5) * inv_scale - 0.5;
      double sd, dsd_dv, dsd_du;
      distance_.Evaluate(vs, us, &sd, &dsd_dv, &dsd_du);
      if (sd > 0.0) {  // inside is free
        residual = sd;
        moving = true;
        if (want_jacobian) {
          Eigen::RowVector2d g_xd(dsd_du * K(0, 0) * inv_scale, (dsd_du * K(0, 1) + dsd_dv * K(1, 1)) * inv_scale);
          const Eigen::RowVector2d g = distorted ? Eigen::RowVector2d(g_xd * DistortionJacobian(camera_, x, y)) : g_xd;
          gradient = Vector3d(g.x() / Xc.z(), g.y() / Xc.z(), -(g.x() * x + g.y() * y) / Xc.z());
        }
      }
    }
    residuals[i] = residual;
    if (!want_jacobian) continue;
    if (moving) {
      for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) coefficients(3 * r + k) = gradient(r) * local(k);
        coefficients(9 + r) = gradient(r);
      }
      row.noalias() = coefficients * dMc;
    }
    int offset = 0;
    for (int b = 0; b < num_blocks; ++b) {
      const int size = parameter_block_sizes()[b];
      if (jacobians[b]) {
        double* out = jacobians[b] + i * size;
        for (int k = 0; k < size; ++k) out[k] = moving && offset + k < num_pose_parameters_ ? row(offset + k) : 0.0;
      }
      offset += size;
    }
  }
  return true;
}

}  // namespace confluent::tracking_internal
