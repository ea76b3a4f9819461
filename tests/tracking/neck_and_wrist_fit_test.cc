// The template bends where a body bends: at the base of the neck (a bowed head moves the head
// forward, not only turns it) and sideways at the wrist (a hand bent across the forearm's plane).
// Ground truth: the studio actor, posed and rendered; the template follows it from the pose it
// had a frame earlier, as the tracker does.

#include <gtest/gtest.h>

#include <vector>

#include "core/skeleton.h"
#include "core/skinning.h"
#include "silhouette/overlap.h"
#include "studio/actor.h"
#include "studio/motion.h"
#include "tests/support/camera_ring.h"
#include "tracking/pose_from_joints.h"
#include "tracking/silhouette_fit.h"

namespace confluent {
namespace {

using Eigen::AngleAxisd;
using Eigen::Vector3d;

TEST(NeckAndWristFit, ABowedHeadAndAHandBentSidewaysAreFollowed) {
  StudioActorOptions actor_options;
  actor_options.target_triangles = 12000;
  const StudioActor actor = BuildStudioActor(actor_options);
  StudioMotionOptions motion;
  motion.num_frames = 1;
  const Pose before = DefaultPerformance(actor.skeleton, motion).front();
  // The next frame: the neck bowed 26 degrees at its base, the left hand bent 29 degrees outwards.
  Pose after = before;
  after.local_rotations[kJointNeck] =
      after.local_rotations[kJointNeck] * Eigen::Quaterniond(AngleAxisd(-0.45, Vector3d::UnitX()));
  after.local_rotations[kJointLeftWrist] =
      after.local_rotations[kJointLeftWrist] * Eigen::Quaterniond(AngleAxisd(0.5, Vector3d::UnitY()));

  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(actor_options.height_m);
  const std::vector<Vector3d> joints_before = JointPositions(actor.skeleton, before);
  const std::vector<Vector3d> truth = JointPositions(actor.skeleton, after);
  const TemplatePose start = FitPoseToJoints(body, shape, joints_before, nullptr, TemplatePose{});

  const Rig rig = testing::CameraRing(8, 480, 360);
  Mesh posed = actor.mesh;
  posed.vertices = SkinVertices(actor.mesh.vertices, actor.weights, actor.skeleton, after);
  std::vector<Image> masks;
  for (const Camera& camera : rig.cameras) masks.push_back(RasterizeClosedMesh(posed, camera));

  SilhouetteFitOptions options;  // a tracking step: the pose only, held near the previous frame
  const SilhouetteObservations observations(rig, masks, {}, options.downscale, options.max_contour_points);
  BodyShape fitted_shape = shape;
  TemplatePose pose = start;
  FitTemplateToSilhouettes(body, observations, options, &fitted_shape, &pose);
  const std::vector<Vector3d> fitted = body.JointPositions(shape, pose);
  const std::vector<Vector3d> started = body.JointPositions(shape, start);

  // The bow moves the head 4-5 cm; a head that only turns on an upright neck stays 2.4 cm off
  // (and the hand of a wrist that only flexes 2.7 cm, its wrist 1.9 cm: the forearm turns).
  const double head_moved = (truth[kJointHead] - joints_before[kJointHead]).norm();
  ASSERT_GT(head_moved, 0.035);
  EXPECT_LT((fitted[kJointHead] - truth[kJointHead]).norm(), 0.012)
      << "started " << (started[kJointHead] - truth[kJointHead]).norm() << " m away";
  // The hand's end swings 9 cm; the forearm stays where it was.
  ASSERT_GT((truth[kJointLeftHandEnd] - joints_before[kJointLeftHandEnd]).norm(), 0.06);
  EXPECT_LT((fitted[kJointLeftHandEnd] - truth[kJointLeftHandEnd]).norm(), 0.02)
      << "started " << (started[kJointLeftHandEnd] - truth[kJointLeftHandEnd]).norm() << " m away";
  EXPECT_LT((fitted[kJointLeftWrist] - truth[kJointLeftWrist]).norm(), 0.015);
}

}  // namespace
}  // namespace confluent
