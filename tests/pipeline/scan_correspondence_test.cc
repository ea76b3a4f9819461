// One register -> place path for run, correspond and animate: a registration seeded by a poor
// tracked shape falls back to the first tracked pose, then to registering from the scan alone;
// a scan in the first tracked frame's pose takes that frame's template as its reference, or, where
// one of its segments is off the scan, the fit, with the first frames eased from it.

#include "pipeline/scan_correspondence.h"

#include <gtest/gtest.h>

#include "pipeline/first_pose_seam.h"
#include "core/error.h"
#include "core/skinning.h"
#include "deform/confluent_motion.h"
#include "silhouette/overlap.h"
#include "studio/actor.h"
#include "tests/support/camera_ring.h"

namespace confluent {
namespace {

TEST(ScanCorrespondence, PoorTrackedShapeFallsBackToRegisteringFromTheScanAlone) {
  StudioActorOptions actor_options;
  actor_options.target_triangles = 12000;
  const StudioActor actor = BuildStudioActor(actor_options);
  const BodyTemplate body;
  // A tracked shape far from the actor's (1.75 m): a 1.1 m body.
  ScanCorrespondenceOptions options;
  options.known_shape = BodyShape::Uniform(1.1);
  ScanRegistrationOptions seeded;
  seeded.fit_shape = false;
  seeded.initial_shape = *options.known_shape;
  EXPECT_THROW(RegisterTemplateToScan(body, actor.mesh, seeded, "actor.ply"), InputError);  // the seeded path alone fails

  const ScanCorrespondence result = CorrespondTemplateToScan(body, actor.mesh, "actor.ply", options);
  bool warned = false;
  for (const std::string& warning : result.registration.warnings)
    warned = warned || warning.find("registered from the scan alone") != std::string::npos;
  EXPECT_TRUE(warned);
  EXPECT_GT(result.correspondences.pairs.size(), 50u);
  // The reference keeps the tracked shape: its height is the 1.1 m body's, not the scan's.
  const double reference_height =
      result.reference.vertices.col(2).maxCoeff() - result.reference.vertices.col(2).minCoeff();
  EXPECT_LT(reference_height, 1.3);
}

// A scan taken in the performer's first pose, deeply crouched with the arms forward (the studio
// actor posed so): the registration from a standing start fails; the one from the first tracked
// frame's pose (the template's crouch, a little off) finds it.
TEST(ScanCorrespondence, CrouchedScanIsRegisteredFromTheFirstTrackedPose) {
  StudioActorOptions actor_options;
  actor_options.target_triangles = 12000;
  const StudioActor actor = BuildStudioActor(actor_options);
  const BodyTemplate body;
  // Rotations about the lateral axis (x; the body faces +y, z up): positive swings a downward
  // segment forwards.
  auto about_x = [](double angle) { return Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX())); };
  Pose crouch = Pose::Rest(actor.skeleton.size());
  crouch.local_rotations[kJointChest] = about_x(-0.3);
  for (int hip : {kJointLeftHip, kJointRightHip}) {
    crouch.local_rotations[hip] = about_x(1.3);
    crouch.local_rotations[hip + 1] = about_x(-2.1);
    crouch.local_rotations[hip + 2] = about_x(0.8);
  }
  for (int shoulder : {kJointLeftShoulder, kJointRightShoulder}) {
    crouch.local_rotations[shoulder] = about_x(1.2);
    crouch.local_rotations[shoulder + 1] = about_x(1.3);
  }
  Mesh scan = actor.mesh;
  scan.vertices = SkinVertices(actor.mesh.vertices, actor.weights, actor.skeleton, crouch, SkinningMethod::kDualQuaternion);
  const BodyShape shape = BodyShape::Uniform(1.75);
  ScanCorrespondenceOptions options;
  options.known_shape = shape;
  ScanRegistrationOptions standing;
  standing.fit_shape = false;
  standing.initial_shape = shape;
  EXPECT_THROW(RegisterTemplateToScan(body, scan, standing, "crouched.ply"), InputError);

  // The tracker's first frame: the template crouched alike, its joint angles a little off.
  TemplatePose tracked;
  tracked.root_translation = WorldFromJoint(actor.skeleton, crouch)[kJointPelvis].translation() -
                             body.JointPositions(shape, TemplatePose())[kJointPelvis];
  tracked.dofs[kJointChest] = {-0.25, 0, 0};
  for (int hip : {kJointLeftHip, kJointRightHip}) {
    tracked.dofs[hip] = {1.2, 0, 0};
    tracked.dofs[hip + 1] = {-1.9, 0, 0};
  }
  options.first_tracked_pose = tracked;
  const ScanCorrespondence result = CorrespondTemplateToScan(body, scan, "crouched.ply", options);
  bool warned = false;
  for (const std::string& warning : result.registration.warnings)
    warned = warned || warning.find("first tracked frame") != std::string::npos;
  EXPECT_TRUE(warned);
  EXPECT_LT(result.registration.trimmed_rms_residual_m, 0.03);
  EXPECT_GT(result.correspondences.pairs.size(), 50u);
}

// The actor scanned with the arms turned from the A-pose and a knee bent, and the template
// registered to it: the first tracked frame of a tracker that did well.
struct HeldPoseScan {
  BodyTemplate body;
  BodyShape shape = BodyShape::Uniform(1.75);
  Mesh scan;
  TemplatePose tracked;
  ScanRegistrationOptions fit;
  HeldPoseScan() {
    StudioActorOptions actor_options;
    actor_options.target_triangles = 12000;
    const StudioActor actor = BuildStudioActor(actor_options);
    auto about = [](double angle, const Eigen::Vector3d& axis) {
      return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis));
    };
    Pose held = Pose::Rest(actor.skeleton.size());
    held.local_rotations[kJointLeftShoulder] = about(0.45, Eigen::Vector3d::UnitY());
    held.local_rotations[kJointRightShoulder] = about(-0.45, Eigen::Vector3d::UnitY());
    held.local_rotations[kJointLeftHip] = about(0.5, Eigen::Vector3d::UnitX());
    held.local_rotations[kJointLeftKnee] = about(-0.8, Eigen::Vector3d::UnitX());
    scan = actor.mesh;
    scan.vertices =
        SkinVertices(actor.mesh.vertices, actor.weights, actor.skeleton, held, SkinningMethod::kDualQuaternion);
    fit.fit_shape = false;
    fit.initial_shape = shape;
    tracked = RegisterTemplateToScan(body, scan, fit, "held.ply").pose;
  }
  // The template's rms residual against the scan in `pose` as it is, and registered from it.
  double RmsAsIs(const TemplatePose& pose) const {
    ScanRegistrationOptions as_is = fit;
    as_is.initial_pose = pose;
    as_is.rounds = 0;
    return RegisterTemplateToScan(body, scan, as_is, "held.ply").rms_residual_m;
  }
  double RmsFittedFrom(const TemplatePose& pose) const {
    ScanRegistrationOptions from = fit;
    from.initial_pose = pose;
    return RegisterTemplateToScan(body, scan, from, "held.ply").rms_residual_m;
  }
};

// The tracker's first frame in the scan's pose: that frame's template is the reference, so
// Confluent Motion gives back the scan at frame 0. A first frame in another pose (arms raised) is a
// pose to register from, not the reference.
TEST(ScanCorrespondence, ScanInTheFirstTrackedPoseIsReproducedAtFrameZero) {
  const HeldPoseScan held;
  const BodyTemplate& body = held.body;
  const BodyShape& shape = held.shape;
  const Mesh& scan = held.scan;
  const TemplatePose& tracked = held.tracked;

  ScanCorrespondenceOptions options;
  options.known_shape = shape;
  options.first_tracked_pose = tracked;
  const ScanCorrespondence result = CorrespondTemplateToScan(body, scan, "held.ply", options);
  bool said = false;
  for (const std::string& warning : result.registration.warnings)
    said = said || warning.find("first tracked frame's pose: that frame's template is the reference") != std::string::npos;
  EXPECT_TRUE(said);
  const Mesh frame0 = body.PosedMesh(shape, tracked);
  EXPECT_LT((result.reference.vertices - frame0.vertices).cwiseAbs().maxCoeff(), 1e-9);
  ConfluentMotion motion(scan, result.reference, result.correspondences);
  const RowMatrixX3d animated = motion.Deform(frame0.vertices);
  EXPECT_LT((animated - scan.vertices).rowwise().norm().maxCoeff(), 1e-4);  // frame 0 is the scan

  // The tracker's first frame with the right forearm bent further than the scan's: the body as a
  // whole still fits the scan about as well as a fit does, but that arm does not. The tracker
  // erred there, so the fit to the scan is the reference.
  TemplatePose bent = tracked;
  bent.dofs[kJointRightElbow][0] += 0.15;
  ASSERT_LT(held.RmsAsIs(bent), 1.25 * held.RmsFittedFrom(bent));  // the whole-body test alone would take it
  options.first_tracked_pose = bent;
  const ScanCorrespondence not_bent = CorrespondTemplateToScan(body, scan, "held.ply", options);
  for (const std::string& warning : not_bent.registration.warnings)
    EXPECT_EQ(warning.find("that frame's template is the reference"), std::string::npos) << warning;
  EXPECT_GT((not_bent.reference.vertices - body.PosedMesh(shape, bent).vertices).cwiseAbs().maxCoeff(), 0.01);
  // The scan still stands in that frame's pose: the first frames ease from the fit into the
  // tracked poses, so frame 0 of the animated scan is the scan, and the seam's end the tracker's.
  ASSERT_TRUE(not_bent.registration.first_tracked_pose);
  FirstPoseSeam seam{not_bent.registration.pose, *not_bent.registration.first_tracked_pose, 10};
  RowMatrixX3d eased = body.PosedMesh(shape, bent).vertices;
  ApplyFirstPoseSeam(body, shape, seam, bent, 0, &eased);
  ConfluentMotion from_fit(scan, not_bent.reference, not_bent.correspondences);
  EXPECT_LT((from_fit.Deform(eased) - scan.vertices).rowwise().norm().maxCoeff(), 1e-3);
  EXPECT_GT((from_fit.Deform(body.PosedMesh(shape, bent).vertices) - scan.vertices).rowwise().norm().maxCoeff(), 0.01);

  // The tracker's first frame with the arms raised: the scan is not in it; registered instead.
  TemplatePose raised = tracked;
  raised.dofs[kJointLeftShoulder][1] += 1.0;
  raised.dofs[kJointRightShoulder][1] -= 1.0;
  options.first_tracked_pose = raised;
  const ScanCorrespondence other = CorrespondTemplateToScan(body, scan, "held.ply", options);
  for (const std::string& warning : other.registration.warnings)
    EXPECT_EQ(warning.find("that frame's template is the reference"), std::string::npos) << warning;
  EXPECT_FALSE(other.registration.first_tracked_pose);
  EXPECT_LT(other.registration.rms_residual_m, 0.015);
}

// The tracker's first frame with the right forearm folded far from the scan's: the body as a whole
// fits the scan too poorly to call it the scan's pose by the residuals, but the first frame's
// silhouettes (here the scan's own, in a ring of cameras) are explained better by the fit: the
// scan stands in that frame's pose, and the first frames ease from the fit. Where the performer
// raised the arms at frame 0 instead, the silhouettes say so.
TEST(ScanCorrespondence, FirstFrameSilhouettesTellATrackersFoldedForearmFromAnotherPose) {
  const HeldPoseScan held;
  const Rig rig = testing::CameraRing(8, 320, 240);
  std::vector<Image> first_masks;
  for (const Camera& camera : rig.cameras) first_masks.push_back(RasterizeClosedMesh(held.scan, camera));
  ScanCorrespondenceOptions options;
  options.known_shape = held.shape;
  const auto overlap = [&](const TemplatePose& pose) {
    return MeanSilhouetteIoU(SilhouetteIoUs(held.body.PosedMesh(held.shape, pose), rig, first_masks, {}));
  };

  TemplatePose folded = held.tracked;
  folded.dofs[kJointRightElbow][0] += 1.2;
  ASSERT_GT(held.RmsAsIs(folded), 1.25 * held.RmsFittedFrom(folded));  // the residuals alone refuse it
  options.first_tracked_pose = folded;
  EXPECT_FALSE(CorrespondTemplateToScan(held.body, held.scan, "held.ply", options).registration.first_tracked_pose);

  options.first_frame_overlap = overlap;
  const ScanCorrespondence result = CorrespondTemplateToScan(held.body, held.scan, "held.ply", options);
  ASSERT_TRUE(result.registration.first_tracked_pose);
  EXPECT_GT(overlap(result.registration.pose), overlap(folded));
  bool said = false;
  for (const std::string& warning : result.registration.warnings)
    said = said || warning.find("explains the first frame's silhouettes") != std::string::npos;
  EXPECT_TRUE(said);
  FirstPoseSeam seam{result.registration.pose, *result.registration.first_tracked_pose, 10};
  RowMatrixX3d eased = held.body.PosedMesh(held.shape, folded).vertices;
  ApplyFirstPoseSeam(held.body, held.shape, seam, folded, 0, &eased);
  ConfluentMotion motion(held.scan, result.reference, result.correspondences);
  EXPECT_LT((motion.Deform(eased) - held.scan.vertices).rowwise().norm().maxCoeff(), 1e-3);  // frame 0 is the scan
  const RowMatrixX3d as_tracked = held.body.PosedMesh(held.shape, folded).vertices;
  EXPECT_GT((motion.Deform(as_tracked) - held.scan.vertices).rowwise().norm().maxCoeff(), 0.05);

  TemplatePose raised = held.tracked;
  raised.dofs[kJointLeftShoulder][1] += 1.0;
  raised.dofs[kJointRightShoulder][1] -= 1.0;
  options.first_tracked_pose = raised;
  EXPECT_TRUE(CorrespondTemplateToScan(held.body, held.scan, "held.ply", options).registration.first_tracked_pose)
      << "silhouettes of the scan's pose: raised arms are the tracker's error";
  const Mesh raised_body = held.body.PosedMesh(held.shape, raised);
  for (int c = 0; c < rig.size(); ++c) first_masks[c] = RasterizeClosedMesh(raised_body, rig.cameras[c]);
  EXPECT_FALSE(CorrespondTemplateToScan(held.body, held.scan, "held.ply", options).registration.first_tracked_pose)
      << "the performer raised the arms";
}

TEST(ScanCorrespondence, WhatIsNoBodyIsStillRefused) {
  Mesh box;
  box.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i) box.vertices.row(i) << (i & 1) * 0.5, (i >> 1 & 1) * 0.5, (i >> 2 & 1) * 1.7;
  box.faces.resize(12, 3);
  box.faces << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5;
  ScanCorrespondenceOptions options;
  options.known_shape = BodyShape::Uniform(1.75);
  EXPECT_THROW(CorrespondTemplateToScan(BodyTemplate(), box, "box.ply", options), InputError);
}

}  // namespace
}  // namespace confluent
