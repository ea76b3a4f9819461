#include "core/skinning.h"

#include <cassert>
#include <cmath>
#include <string>

#include "core/error.h"

namespace confluent {

void SkinWeights::Check(int num_joints, const std::string& source) const {
  if (weights.rows() != joints.rows())
    throw InputError(source, "skin weights: " + std::to_string(joints.rows()) + " joint rows but " +
                                 std::to_string(weights.rows()) + " weight rows");
  for (int i = 0; i < joints.rows(); ++i) {
    double sum = 0.0;
    for (int k = 0; k < kMaxInfluences; ++k) {
      const int joint = joints(i, k);
      const double weight = weights(i, k);
      if (joint < -1 || joint >= num_joints)
        throw InputError(source, "skin weights: vertex " + std::to_string(i) + " has joint index " +
                                     std::to_string(joint) + " outside [-1, " + std::to_string(num_joints) + ")");
      if (!std::isfinite(weight) || weight < 0.0)
        throw InputError(source, "skin weights: vertex " + std::to_string(i) + " has a negative or non-finite weight");
      if (joint >= 0) sum += weight;
    }
    if (std::abs(sum - 1.0) > 1e-6)
      throw InputError(source, "skin weights: the weights of vertex " + std::to_string(i) + " sum to " +
                                   std::to_string(sum) + ", not 1");
  }
}

std::vector<Eigen::Isometry3d> SkinningTransforms(const Skeleton& skeleton, const Pose& pose) {
  const std::vector<Eigen::Isometry3d> posed = WorldFromJoint(skeleton, pose);
  const std::vector<Eigen::Vector3d> rest = skeleton.RestPositions();
  std::vector<Eigen::Isometry3d> transforms(posed.size());
  for (std::size_t j = 0; j < posed.size(); ++j) {
    // posed * (p - rest): linear part R, translation t - R * rest (exactly 0 at the rest pose).
    transforms[j].linear() = posed[j].linear();
    transforms[j].translation() = posed[j].translation() - posed[j].linear() * rest[j];
    transforms[j].makeAffine();
  }
  return transforms;
}

namespace {

// A unit dual quaternion q_real + eps q_dual for a rigid transform.
struct DualQuaternion {
  Eigen::Quaterniond real;
  Eigen::Quaterniond dual;
};

DualQuaternion ToDualQuaternion(const Eigen::Isometry3d& transform) {
  DualQuaternion dq;
  dq.real = Eigen::Quaterniond(transform.linear()).normalized();
  const Eigen::Vector3d& t = transform.translation();
  const Eigen::Quaterniond t_quat(0.0, t.x(), t.y(), t.z());
  dq.dual.coeffs() = 0.5 * (t_quat * dq.real).coeffs();
  return dq;
}

}  // namespace

RowMatrixX3d SkinVertices(const RowMatrixX3d& rest_vertices, const SkinWeights& weights,
                          const Skeleton& skeleton, const Pose& pose, SkinningMethod method) {
  assert(weights.num_vertices() == rest_vertices.rows());
  const std::vector<Eigen::Isometry3d> transforms = SkinningTransforms(skeleton, pose);
  const int n = static_cast<int>(rest_vertices.rows());
  RowMatrixX3d posed(n, 3);
  if (method == SkinningMethod::kLinear) {
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d p = rest_vertices.row(i).transpose();
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int k = 0; k < SkinWeights::kMaxInfluences; ++k) {
        const int joint = weights.joints(i, k);
        if (joint < 0 || weights.weights(i, k) == 0.0) continue;
        sum += weights.weights(i, k) * (transforms[joint] * p);
      }
      posed.row(i) = sum.transpose();
    }
    return posed;
  }
  std::vector<DualQuaternion> dqs(transforms.size());
  for (std::size_t j = 0; j < transforms.size(); ++j) dqs[j] = ToDualQuaternion(transforms[j]);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = rest_vertices.row(i).transpose();
    Eigen::Vector4d real = Eigen::Vector4d::Zero(), dual = Eigen::Vector4d::Zero();
    int first = -1;
    for (int k = 0; k < SkinWeights::kMaxInfluences; ++k) {
      const int joint = weights.joints(i, k);
      const double w = weights.weights(i, k);
      if (joint < 0 || w == 0.0) continue;
      if (first < 0) first = joint;
      // Antipodality: blend every quaternion in the hemisphere of the first one.
      const double sign = dqs[joint].real.coeffs().dot(dqs[first].real.coeffs()) < 0.0 ? -1.0 : 1.0;
      real += sign * w * dqs[joint].real.coeffs();
      dual += sign * w * dqs[joint].dual.coeffs();
    }
    if (first < 0) {
      posed.row(i) = p.transpose();
      continue;
    }
    const double norm = real.norm();
    real /= norm;
    dual /= norm;
    const Eigen::Quaterniond qr(real(3), real(0), real(1), real(2));
    const Eigen::Quaterniond qd(dual(3), dual(0), dual(1), dual(2));
    // Translation t = 2 * qd * conj(qr); rotation from qr.
    const Eigen::Quaterniond t_quat = qd * qr.conjugate();
    const Eigen::Vector3d translation = 2.0 * t_quat.vec();
    posed.row(i) = (qr * p + translation).transpose();
  }
  return posed;
}

}  // namespace confluent
