#include "tracking/template_motion.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace confluent {
namespace {

using Eigen::Vector3d;

// The horizontal facing direction of a body with joint positions `p`: (left hip - right hip) x z.
Vector3d Heading(const std::vector<Vector3d>& p) {
  Vector3d f = (p[kJointLeftHip] - p[kJointRightHip]).cross(Vector3d::UnitZ());
  f.z() = 0;
  return f;
}

double LowestFoot(const std::vector<Vector3d>& p) {
  return std::min({p[kJointLeftAnkle].z(), p[kJointRightAnkle].z(), p[kJointLeftToe].z(), p[kJointRightToe].z()});
}

}  // namespace

Mesh PosedTemplateMesh(const BodyTemplate& body, const BodyShape& shape, const Pose& pose) {
  Mesh mesh = body.PosedMesh(shape, TemplatePose());
  const Skeleton skeleton = body.MakeSkeleton(shape);
  const std::vector<Vector3d> rest = skeleton.RestPositions();
  const std::vector<Eigen::Isometry3d> world = WorldFromJoint(skeleton, pose);
  const int nv = static_cast<int>(body.mesh_coords().size());
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const int j = body.segments()[v / nv].joint;
    const Vector3d p = mesh.vertices.row(v).transpose();
    mesh.vertices.row(v) = (world[j] * (p - rest[j])).transpose();
  }
  return mesh;
}

void PlaceMotionAtReference(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& reference,
                            std::vector<Pose>* motion) {
  if (motion->empty()) return;
  const Skeleton skeleton = body.MakeSkeleton(shape);
  const std::vector<Vector3d> ref = confluent::JointPositions(skeleton, body.ToPose(reference));
  const std::vector<Vector3d> first = confluent::JointPositions(skeleton, motion->front());
  const Vector3d a = Heading(first), b = Heading(ref);
  double yaw = 0;
  if (a.norm() > 1e-9 && b.norm() > 1e-9) yaw = std::atan2(a.normalized().cross(b.normalized()).z(), a.normalized().dot(b.normalized()));
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(yaw, Vector3d::UnitZ()));
  const Vector3d from(first[0].x(), first[0].y(), 0), to(ref[0].x(), ref[0].y(), 0);
  const Vector3d offset = skeleton.joints[0].offset_in_parent;
  double low = std::numeric_limits<double>::max();
  for (Pose& pose : *motion) {
    const Vector3d root = offset + pose.root_translation;
    pose.root_translation = turn * (root - from) + to - offset;
    pose.local_rotations[0] = (turn * pose.local_rotations[0]).normalized();
    low = std::min(low, LowestFoot(confluent::JointPositions(skeleton, pose)));
  }
  const double dz = LowestFoot(ref) - low;
  for (Pose& pose : *motion) pose.root_translation.z() += dz;
}

void TemplateBvhMotionOptions::Check() const {
  retarget.Check();
  const std::string owner = "TemplateBvhMotionOptions.";
  RequireOption(fps > 0 && std::isfinite(fps), owner + "fps", fps, "> 0 and finite (--fps)");
  RequireOption(speed > 0 && std::isfinite(speed), owner + "speed", speed, "> 0 and finite (--speed)");
  RequireOption(max_frames >= 1, owner + "max_frames", max_frames, ">= 1 (--frames)");
}

std::vector<Pose> TemplateMotionFromBvh(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& reference,
                                        const std::string& bvh_path, const TemplateBvhMotionOptions& options,
                                        BvhRetargetResult* retarget) {
  options.Check();
  BvhRetargetResult result = RetargetBvhFile(bvh_path, body.MakeSkeleton(shape), options.retarget);
  std::vector<Pose> poses = SampleRetargetedMotion(result, options.fps, options.speed, options.max_frames);
  PlaceMotionAtReference(body, shape, reference, &poses);
  if (retarget) {
    result.poses.clear();
    *retarget = std::move(result);
  }
  return poses;
}

}  // namespace confluent
