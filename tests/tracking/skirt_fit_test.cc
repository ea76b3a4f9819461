// The template's skirt DOF (BodyShape::skirt_length_m, skirt_flare_m): geometry, poses.json
// round trip, recovery of a known skirt from the template's own masks, and the automatic
// initialisation choosing a skirt for a skirted body.

#include <gtest/gtest.h>

#include <cmath>

#include "calib/rig_check.h"
#include "core/error.h"
#include "silhouette/overlap.h"
#include "tests/support/test_support.h"
#include "tracking/motion_io.h"
#include "tracking/silhouette_fit.h"
#include "tracking/tracker.h"
#include "tests/support/camera_ring.h"

namespace confluent {
namespace {

// A standing pose with the arms away from the body.
TemplatePose StandingPose() {
  TemplatePose pose;
  pose.root_translation = Eigen::Vector3d(0.1, -0.05, 0.0);
  pose.root_rotation = Eigen::Vector3d(0, 0, 0.7);
  pose.dofs[kJointLeftShoulder] = {0.2, 0.5, 0.0};
  pose.dofs[kJointRightShoulder] = {-0.1, -0.4, 0.0};
  pose.dofs[kJointLeftElbow] = {0.5, 0, 0};
  return pose;
}

BodyShape SkirtedShape() {
  BodyShape shape = BodyShape::Uniform(1.65);
  shape.skirt_length_m = 0.62;
  shape.skirt_flare_m = 0.13;
  return shape;
}

double LowestZ(const Mesh& mesh, BodySegment segment) {
  double z = 1e9;
  for (int f = 0; f < mesh.faces.rows(); ++f)
    if (mesh.face_labels[f] == int(segment))
      for (int k = 0; k < 3; ++k) z = std::min(z, mesh.vertices(mesh.faces(f, k), 2));
  return z;
}

TEST(SkirtFit, SkirtExtendsTheLowerTorsoDownAndRoundTripsThroughPosesJson) {
  const BodyTemplate body;
  const BodyShape plain = BodyShape::Uniform(1.65);
  const BodyShape skirted = SkirtedShape();
  const TemplatePose rest;
  const double plain_z = LowestZ(body.PosedMesh(plain, rest), BodySegment::kLowerTorso);
  const double skirted_z = LowestZ(body.PosedMesh(skirted, rest), BodySegment::kLowerTorso);
  // The capsule's lower end moves down by the skirt length (its cap grows a little less than
  // the radii, so allow a centimetre); nothing else changes.
  EXPECT_NEAR(plain_z - skirted_z, skirted.skirt_length_m, 0.01);
  EXPECT_NEAR(LowestZ(body.PosedMesh(plain, rest), BodySegment::kHead),
              LowestZ(body.PosedMesh(skirted, rest), BodySegment::kHead), 1e-12);
  const auto plain_joints = body.JointPositions(plain, rest), skirted_joints = body.JointPositions(skirted, rest);
  for (std::size_t j = 0; j < plain_joints.size(); ++j) EXPECT_LT((plain_joints[j] - skirted_joints[j]).norm(), 1e-12);

  testing::TempDir dir;
  TrackedFrame frame;
  frame.pose = StandingPose();
  const std::string path = dir.path() + "/poses.json";
  WritePosesJson(path, body, skirted, {}, {frame}, 25.0);
  const PosesFile file = ReadPosesJson(path, body);
  EXPECT_DOUBLE_EQ(file.shape.skirt_length_m, skirted.skirt_length_m);
  EXPECT_DOUBLE_EQ(file.shape.skirt_flare_m, skirted.skirt_flare_m);
}

// The skirt's length and flare are recovered from the template's own masks, from a start
// that is too short and too narrow, together with the pose.
TEST(SkirtFit, RecoversAKnownSkirtFromItsMasks) {
  const BodyTemplate body;
  const BodyShape truth = SkirtedShape();
  const Rig rig = testing::CameraRing(8, 320, 240, 0.3, 1.4, 0.5, Eigen::Vector3d(0, 0, 0.9));
  const TemplatePose pose_truth = StandingPose();
  const Mesh mesh = body.PosedMesh(truth, pose_truth);
  std::vector<Image> masks;
  for (const Camera& camera : rig.cameras) masks.push_back(RasterizeClosedMesh(mesh, camera));
  SilhouetteFitOptions options;
  options.downscale = 1;
  options.max_contour_points = 400;
  options.rounds = 4;
  options.max_iterations = 25;
  options.fit_shape = true;
  const SilhouetteObservations observations(rig, masks, {}, options.downscale, options.max_contour_points);
  BodyShape shape = BodyShape::Uniform(1.65);
  shape.skirt_length_m = 0.4;
  shape.skirt_flare_m = 0.05;
  TemplatePose pose = pose_truth;
  pose.root_translation += Eigen::Vector3d(0.02, -0.02, 0.01);
  FitTemplateToSilhouettes(body, observations, options, &shape, &pose);
  EXPECT_NEAR(shape.skirt_length_m, truth.skirt_length_m, 0.05);
  EXPECT_NEAR(shape.skirt_flare_m, truth.skirt_flare_m, 0.025);
  // The overlap is close everywhere (not perfect: the legs hidden in the skirt are seen only
  // at the feet, so their lengths and girths drift within the shape prior).
  const Mesh fitted = body.PosedMesh(shape, pose);
  for (std::size_t c = 0; c < rig.cameras.size(); ++c)
    EXPECT_GT(MaskIoU(RasterizeClosedMesh(fitted, rig.cameras[c]), masks[c]), 0.89) << c;
}

// Fully automatic: the initialisation of a skirted body ends with a skirt and a close overlap
// (and that of a body without one, in silhouette_fit_test.cc, with none).
TEST(SkirtFit, InitialisationFindsTheSkirt) {
  const BodyTemplate body;
  const BodyShape truth = SkirtedShape();
  const Rig rig = testing::CameraRing(6, 240, 180, 0.3, 1.4, 0.5, Eigen::Vector3d(0, 0, 0.9));
  const Mesh mesh = body.PosedMesh(truth, StandingPose());
  std::vector<Image> masks;
  for (const Camera& camera : rig.cameras) masks.push_back(RasterizeClosedMesh(mesh, camera));
  TrackerOptions options;
  options.init_rounds = 2;
  Tracker tracker(rig, {}, options);
  const TrackedFrame result = tracker.Initialize(0, masks);
  ASSERT_TRUE(tracker.initialized());
  EXPECT_GT(result.mean_iou, 0.88);
  EXPECT_NEAR(tracker.shape().skirt_length_m, truth.skirt_length_m, 0.1);
  EXPECT_NEAR(tracker.shape().skirt_flare_m, truth.skirt_flare_m, 0.04);
}

TEST(SkirtFit, OutOfRangeSkirtOptionsAreUsageErrors) {
  SilhouetteFitOptions fit;
  fit.skirt_prior_weight = -1.0;
  EXPECT_THROW(fit.Check(), UsageError);
  TrackerOptions tracker;
  tracker.skirt_min_iou_gain = 1.0;
  EXPECT_THROW(tracker.Check(), UsageError);
  tracker.skirt_min_iou_gain = 0.01;
  EXPECT_NO_THROW(tracker.Check());
  tracker.skirt_try_below_iou = 1.5;
  EXPECT_THROW(tracker.Check(), UsageError);
}

}  // namespace
}  // namespace confluent
