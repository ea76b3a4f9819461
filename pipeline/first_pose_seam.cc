#include "pipeline/first_pose_seam.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace confluent {

using Eigen::AngleAxisd;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

constexpr double kSeamSeconds = 0.4;

Matrix3d FromRotationVector(const Vector3d& v) {
  const double angle = v.norm();
  return angle > 0.0 ? AngleAxisd(angle, v / angle).toRotationMatrix() : Matrix3d::Identity();
}

Vector3d ToRotationVector(const Matrix3d& rotation) {
  const AngleAxisd angle_axis(rotation);
  return angle_axis.angle() * angle_axis.axis();
}

// `tracked` turned by `weight` of the rotation that takes `from` to `to` (rotation vectors).
Vector3d CorrectRotation(const Vector3d& tracked, const Vector3d& from, const Vector3d& to, double weight) {
  const Vector3d correction = ToRotationVector(FromRotationVector(to) * FromRotationVector(from).transpose());
  return ToRotationVector(FromRotationVector(weight * correction) * FromRotationVector(tracked));
}

// The difference of two angles, wrapped into (-pi, pi].
double AngleDifference(double to, double from) { return std::remainder(to - from, 2.0 * M_PI); }

}  // namespace

int FirstPoseSeamFrames(double fps) { return std::max(2, static_cast<int>(std::lround(kSeamSeconds * fps))); }

double FirstPoseSeamWeight(const FirstPoseSeam& seam, int frame) {
  if (frame <= 0) return 1.0;
  if (frame >= seam.frames || frame >= seam.tracked_from) return 0.0;
  return 0.5 * (1.0 + std::cos(M_PI * frame / seam.frames));
}

int FirstPoseSeamEnd(const BodyTemplate& body, const FirstPoseSeam& seam,
                     const std::function<const TemplatePose*(int)>& tracked,
                     const std::function<std::optional<double>(int, const TemplatePose&)>& overlap) {
  for (int frame = 1; frame < seam.frames; ++frame) {
    const TemplatePose* pose = tracked(frame);
    if (!pose) break;
    const std::optional<double> as_tracked = overlap(frame, *pose);
    const std::optional<double> corrected = as_tracked ? overlap(frame, FirstPoseSeamPose(body, seam, *pose, frame))
                                                       : std::nullopt;
    if (!corrected) break;
    if (*as_tracked > *corrected) return frame;
  }
  return seam.frames;
}

TemplatePose FirstPoseSeamPose(const BodyTemplate& body, const FirstPoseSeam& seam, const TemplatePose& tracked,
                               int frame) {
  const double weight = FirstPoseSeamWeight(seam, frame);
  if (weight == 0.0) return tracked;
  TemplatePose pose = tracked;
  pose.root_translation += weight * (seam.registered.root_translation - seam.first_tracked.root_translation);
  pose.root_rotation =
      CorrectRotation(tracked.root_rotation, seam.first_tracked.root_rotation, seam.registered.root_rotation, weight);
  for (int j = 0; j < kNumTemplateJoints; ++j) {
    const JointDof& dof = body.dofs()[j];
    const auto& from = seam.first_tracked.dofs[j];
    const auto& to = seam.registered.dofs[j];
    if (dof.type == JointType::kBall) {
      const Vector3d turned = CorrectRotation(Vector3d(tracked.dofs[j][0], tracked.dofs[j][1], tracked.dofs[j][2]),
                                              Vector3d(from[0], from[1], from[2]), Vector3d(to[0], to[1], to[2]), weight);
      for (int k = 0; k < 3; ++k) pose.dofs[j][k] = turned[k];
    } else {
      for (int k = 0; k < dof.num_dof(); ++k) pose.dofs[j][k] += weight * AngleDifference(to[k], from[k]);
    }
  }
  return pose;
}

void ApplyFirstPoseSeam(const BodyTemplate& body, const BodyShape& shape, const FirstPoseSeam& seam,
                        const TemplatePose& tracked, int frame, RowMatrixX3d* vertices) {
  if (FirstPoseSeamWeight(seam, frame) == 0.0) return;
  *vertices += body.PosedMesh(shape, FirstPoseSeamPose(body, seam, tracked, frame)).vertices -
               body.PosedMesh(shape, tracked).vertices;
}

}  // namespace confluent
