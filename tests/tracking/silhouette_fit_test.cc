#include "tracking/silhouette_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "calib/rig_check.h"
#include "core/error.h"
#include "silhouette/overlap.h"
#include "tracking/tracker.h"
#include "tests/support/camera_ring.h"
#include "tests/support/template_masks.h"

namespace confluent {
namespace {

TemplatePose TruePose() {
  TemplatePose pose;
  pose.root_translation = Eigen::Vector3d(0.05, -0.1, 0.0);
  pose.root_rotation = Eigen::Vector3d(0, 0, 0.5);
  pose.dofs[kJointSpine] = {-0.15, 0.05, 0.1};
  pose.dofs[kJointLeftShoulder] = {0.4, 0.9, 0.0};
  pose.dofs[kJointLeftElbow] = {0.8, 0, 0};
  pose.dofs[kJointRightShoulder] = {-0.3, -0.5, 0.0};
  pose.dofs[kJointRightElbow] = {0.4, 0, 0};
  pose.dofs[kJointLeftHip] = {0.5, 0.1, 0.0};
  pose.dofs[kJointLeftKnee] = {-0.7, 0, 0};
  pose.dofs[kJointRightHip] = {-0.1, -0.1, 0.0};
  pose.dofs[kJointHead] = {0.1, 0.0, 0.3};
  return pose;
}

// A thorough shape-and-pose fit at full mask resolution.
SilhouetteFitOptions FullResolutionShapeFit() {
  SilhouetteFitOptions options;
  options.downscale = 1;
  options.max_contour_points = 400;
  options.rounds = 3;
  options.max_iterations = 25;
  options.fit_shape = true;
  return options;
}

double MeanJointError(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& a, const TemplatePose& b) {
  const auto ja = body.JointPositions(shape, a), jb = body.JointPositions(shape, b);
  double sum = 0;
  for (std::size_t j = 0; j < ja.size(); ++j) sum += (ja[j] - jb[j]).norm();
  return sum / ja.size();
}

TEST(SilhouetteFit, RecoversAKnownPoseFromAPerturbedStart) {
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.7);
  const Rig rig = testing::CameraRing(6, 320, 240);
  const TemplatePose truth = TruePose();
  const Mesh mesh = body.PosedMesh(shape, truth);
  std::vector<Image> masks;
  for (const Camera& camera : rig.cameras) masks.push_back(RasterizeSilhouette(mesh, camera, 1));
  // Perturb every DOF and the root.
  TemplatePose start = truth;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-0.15, 0.15);
  for (int j = 1; j < kNumTemplateJoints; ++j)
    for (int k = 0; k < body.dofs()[j].num_dof(); ++k) start.dofs[j][k] += angle(rng);
  start.root_translation += Eigen::Vector3d(0.04, -0.03, 0.02);
  start.root_rotation.z() += 0.1;
  body.ClampToLimits(&start);
  const double start_error = MeanJointError(body, shape, start, truth);
  EXPECT_GT(start_error, 0.03);
  SilhouetteFitOptions options;
  options.downscale = 1;
  options.max_contour_points = 300;
  options.rounds = 4;
  options.max_iterations = 30;
  options.prior_weight = 0.0;
  const SilhouetteObservations observations(rig, masks, {}, options.downscale, options.max_contour_points);
  EXPECT_EQ(observations.num_used_cameras(), 6);
  BodyShape fitted_shape = shape;
  TemplatePose pose = start;
  const SilhouetteFitSummary summary = FitTemplateToSilhouettes(body, observations, options, &fitted_shape, &pose);
  const double error = MeanJointError(body, shape, pose, truth);
  EXPECT_LT(error, 0.01) << "start " << start_error << " iterations " << summary.iterations;
  EXPECT_LT(summary.mean_outside_px, 0.5);
  // The overlap is near perfect in every camera.
  const Mesh fitted = body.PosedMesh(shape, pose);
  for (std::size_t c = 0; c < rig.cameras.size(); ++c)
    EXPECT_GT(MaskIoU(RasterizeSilhouette(fitted, rig.cameras[c], 1), masks[c]), 0.93) << c;
}

TEST(SilhouetteFit, InitialisesShapeAndPoseFromTheVisualHull) {
  const BodyTemplate body;
  BodyShape truth_shape = BodyShape::Uniform(1.65);
  truth_shape.girth_scale[int(BodySegment::kUpperTorso)] *= 1.1;
  truth_shape.length_scale[int(BodySegment::kLeftThigh)] *= 1.05;
  truth_shape.length_scale[int(BodySegment::kRightThigh)] *= 1.05;
  const Rig rig = testing::CameraRing(6, 320, 240);
  TemplatePose truth;
  truth.root_translation = Eigen::Vector3d(0.2, 0.1, 0.0);
  truth.root_rotation = Eigen::Vector3d(0, 0, 2.2);
  truth.dofs[kJointLeftShoulder] = {0.0, 0.8, 0.0};  // nearly a T-pose
  truth.dofs[kJointRightShoulder] = {0.0, -0.8, 0.0};
  const Mesh mesh = body.PosedMesh(truth_shape, truth);
  std::vector<Image> masks;
  for (const Camera& camera : rig.cameras) masks.push_back(RasterizeSilhouette(mesh, camera, 1));
  const HullPlacement placement = EstimatePlacementFromHull(rig, masks, {});
  ASSERT_TRUE(placement.ok);
  EXPECT_NEAR(placement.height_m, 1.65, 0.1);
  EXPECT_NEAR(placement.floor_z, 0.0, 0.06);
  Tracker tracker(rig, {});
  const TrackedFrame result = tracker.Initialize(0, masks);
  ASSERT_TRUE(tracker.initialized());
  const auto joints = tracker.body().JointPositions(tracker.shape(), result.pose);
  // The frame's joints are those of the shape kept (the landmarks' check compares them).
  ASSERT_EQ(result.joints.size(), joints.size());
  for (std::size_t j = 0; j < joints.size(); ++j) EXPECT_LT((result.joints[j] - joints[j]).norm(), 1e-9) << j;
  const auto expected = body.JointPositions(truth_shape, truth);
  double sum = 0;
  for (std::size_t j = 0; j < joints.size(); ++j) sum += (joints[j] - expected[j]).norm();
  EXPECT_LT(sum / joints.size(), 0.03);
  EXPECT_GT(result.mean_iou, 0.9);
  // No skirt where there is none (the skirt hypothesis does not win).
  EXPECT_EQ(tracker.shape().skirt_length_m, 0.0);
  EXPECT_EQ(tracker.shape().skirt_flare_m, 0.0);
}

// The contour rays run through the silhouette's edge, not through the centres of its border
// pixels: at a low resolution (limbs about 10 px across) the fitted girths of a template with
// known, thicker-than-generic girths match the truth instead of coming out half a pixel thin.
// (The head is left out: its length and girth trade against each other.)
TEST(SilhouetteFit, RecoversKnownGirthsWithoutShrinking) {
  const BodyTemplate body;
  const BodyShape start_shape = BodyShape::Uniform(1.7);
  BodyShape truth_shape = start_shape;
  for (double& g : truth_shape.girth_scale) g *= 1.12;
  const Rig rig = testing::CameraRing(8, 320, 240);
  const TemplatePose truth = TruePose();
  const std::vector<Image> masks = testing::TemplateMasks(body, truth_shape, truth, rig);  // centre-sampled
  SilhouetteFitOptions options = FullResolutionShapeFit();
  options.shape_prior_weight = 1.0;
  options.fit_sections = false;  // girths alone: depth and taper would trade against them
  const SilhouetteObservations observations(rig, masks, {}, options.downscale, options.max_contour_points);
  BodyShape shape = start_shape;
  TemplatePose pose = truth;
  FitTemplateToSilhouettes(body, observations, options, &shape, &pose);
  for (BodySegment s : {BodySegment::kUpperTorso, BodySegment::kLowerTorso, BodySegment::kLeftThigh,
                        BodySegment::kLeftShank, BodySegment::kLeftUpperArm}) {
    const double ratio = shape.girth_scale[int(s)] / truth_shape.girth_scale[int(s)];
    EXPECT_NEAR(ratio, 1.0, 0.035) << BodySegmentName(int(s));
  }
  // And the fitted template covers the masks: IoU near 1 in every camera, with no systematic
  // shortfall (fewer template pixels than mask pixels by at most 4%).
  const Mesh fitted = body.PosedMesh(shape, pose);
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    const Image rendered = RasterizeClosedMesh(fitted, rig.cameras[c]);
    EXPECT_GT(MaskIoU(rendered, masks[c]), 0.92) << c;
    EXPECT_GT(static_cast<double>(CountForeground(rendered)) / CountForeground(masks[c]), 0.96) << c;
  }
}

// Cross-sections along the bone (issue 19, part 3): a body whose chest is deeper and lies further
// in front of the spine, whose hips are narrower than the waist, whose thighs are deeper and whose
// upper arms bulge more than the generic template's. The fit from the generic cross-sections finds them, and the template
// then covers the masks better than one fitted with girths alone.
TEST(SilhouetteFit, RecoversKnownCrossSections) {
  const BodyTemplate body;
  const BodyShape start_shape = BodyShape::Uniform(1.7);
  BodyShape truth_shape = start_shape;
  const int chest = int(BodySegment::kUpperTorso), hips = int(BodySegment::kLowerTorso);
  truth_shape.depth_scale[chest] = 1.25;
  truth_shape.depth_offset[chest] = 0.2;
  truth_shape.taper_scale[hips] = 1.2;  // the waist (end B) wider than the hips
  for (BodySegment s : {BodySegment::kLeftThigh, BodySegment::kRightThigh}) truth_shape.depth_scale[int(s)] = 1.15;
  for (BodySegment s : {BodySegment::kLeftUpperArm, BodySegment::kRightUpperArm}) truth_shape.mid_bulge[int(s)] = 0.2;
  const Rig rig = testing::CameraRing(8, 320, 240);
  const TemplatePose truth = TruePose();
  const std::vector<Image> masks = testing::TemplateMasks(body, truth_shape, truth, rig);
  SilhouetteFitOptions options = FullResolutionShapeFit();
  options.shape_prior_weight = 1.0;
  options.section_prior_weight = 1.0;
  options.depth_offset_prior_weight = 1.0;  // from the true pose the offset is seen (not so in a bent torso)
  const SilhouetteObservations observations(rig, masks, {}, options.downscale, options.max_contour_points);
  auto fit = [&](bool sections, BodyShape* shape, TemplatePose* pose) {
    SilhouetteFitOptions o = options;
    o.fit_sections = sections;
    *shape = start_shape;
    *pose = truth;
    FitTemplateToSilhouettes(body, observations, o, shape, pose);
  };
  BodyShape with, without;
  TemplatePose pose_with, pose_without;
  fit(true, &with, &pose_with);
  fit(false, &without, &pose_without);
  EXPECT_NEAR(with.depth_scale[chest], 1.25, 0.08);
  EXPECT_NEAR(with.depth_offset[chest], 0.2, 0.08);
  EXPECT_NEAR(with.taper_scale[hips], 1.2, 0.08);
  EXPECT_NEAR(with.depth_scale[int(BodySegment::kLeftThigh)], 1.15, 0.08);
  EXPECT_NEAR(with.depth_scale[int(BodySegment::kRightThigh)], 1.15, 0.08);
  EXPECT_NEAR(with.mid_bulge[int(BodySegment::kLeftUpperArm)], 0.2, 0.08);
  for (double v : without.depth_scale) EXPECT_EQ(v, 1.0);
  const Mesh mesh_with = body.PosedMesh(with, pose_with), mesh_without = body.PosedMesh(without, pose_without);
  double iou_with = 0, iou_without = 0;
  for (std::size_t c = 0; c < rig.cameras.size(); ++c) {
    iou_with += MaskIoU(RasterizeClosedMesh(mesh_with, rig.cameras[c]), masks[c]) / rig.size();
    iou_without += MaskIoU(RasterizeClosedMesh(mesh_without, rig.cameras[c]), masks[c]) / rig.size();
  }
  EXPECT_GT(iou_with, 0.95);
  EXPECT_GT(iou_with, iou_without + 0.01);
}

// A first frame in a deep crouch (issue 19: Indian dance starts in a plie): the visual hull is
// lower than the performer, so the initial shape starts too small. With the tracker's initial
// shape priors (a weak pull towards that size, a strong one towards human proportions) the fit
// finds the body's size and proportions; with a strong pull towards the start it cannot.
TEST(SilhouetteFit, CrouchedFirstFrameFindsTheBodysSizeAndProportions) {
  const BodyTemplate body;
  const BodyShape truth_shape = BodyShape::Uniform(1.75);  // every scale 1
  TemplatePose crouch;
  crouch.root_rotation = Eigen::Vector3d(0, 0, 0.4);
  crouch.dofs[kJointChest] = {0.3, 0.0, 0.0};
  crouch.dofs[kJointLeftHip] = {0.9, 0.25, 0.3};
  crouch.dofs[kJointRightHip] = {0.9, -0.25, -0.3};
  crouch.dofs[kJointLeftKnee] = {-1.4, 0, 0};
  crouch.dofs[kJointRightKnee] = {-1.4, 0, 0};
  crouch.dofs[kJointLeftAnkle] = {0.5, 0, 0};
  crouch.dofs[kJointRightAnkle] = {0.5, 0, 0};
  crouch.dofs[kJointLeftShoulder] = {0.0, 0.9, 0.0};
  crouch.dofs[kJointRightShoulder] = {0.0, -0.9, 0.0};
  const Rig rig = testing::CameraRing(8, 320, 240);
  const std::vector<Image> masks = testing::TemplateMasks(body, truth_shape, crouch, rig);
  const TrackerOptions tracker;
  SilhouetteFitOptions options = FullResolutionShapeFit();
  options.fit_skirt = false;
  options.prior_weight = 0.2;
  options.rounds = tracker.init_rounds;  // the tracker's initial fit
  options.max_iterations = tracker.init_max_iterations;
  const SilhouetteObservations observations(rig, masks, {}, options.downscale, options.max_contour_points);
  auto fit = [&](double prior_weight, double proportion_weight) {
    SilhouetteFitOptions o = options;
    o.shape_prior_weight = prior_weight;
    o.shape_proportion_weight = proportion_weight;
    BodyShape shape = BodyShape::Uniform(1.5);  // what a crouched hull's height suggests
    TemplatePose pose = crouch;
    FitTemplateToSilhouettes(body, observations, o, &shape, &pose);
    return shape;
  };
  const BodyShape fitted = fit(tracker.init_shape_prior_weight, tracker.init_shape_proportion_weight);
  const BodyShape pulled = fit(20.0, 0.0);  // the per-frame default: held near the start
  auto mean_length = [](const BodyShape& s) {
    double sum = 0;
    for (double l : s.length_scale) sum += l;
    return sum / s.length_scale.size();
  };
  EXPECT_NEAR(mean_length(fitted), 1.0, 0.05);
  EXPECT_LT(mean_length(pulled), 0.95);
  // Shank and foot are left out: in a deep crouch their lengths trade against the knee and
  // ankle angles (they come out 10-25% short here).
  for (BodySegment s : {BodySegment::kUpperTorso, BodySegment::kLowerTorso, BodySegment::kLeftThigh,
                        BodySegment::kLeftUpperArm, BodySegment::kLeftForearm, BodySegment::kNeck})
    EXPECT_NEAR(fitted.length_scale[int(s)], 1.0, 0.05) << BodySegmentName(int(s));
}

TEST(SilhouetteFit, MasksAreReducedToTheRequestedWidthUnlessTheFactorIsGiven) {
  EXPECT_EQ(FitReductionFactor(0, 1024, 256), 4);
  EXPECT_EQ(FitReductionFactor(0, 1024, 512), 2);
  EXPECT_EQ(FitReductionFactor(0, 1920, 512), 4);  // 3.75 rounded
  EXPECT_EQ(FitReductionFactor(0, 320, 512), 1);   // never enlarged
  EXPECT_EQ(FitReductionFactor(3, 1024, 256), 3);  // an explicit factor wins
  // The tracker tracks at about 512 pixels across and fits the first frame at 256.
  const TrackerOptions defaults;
  EXPECT_EQ(FitReductionFactor(defaults.fit.downscale, 1024, defaults.fit.automatic_width), 2);
  EXPECT_EQ(FitReductionFactor(defaults.fit.downscale, 1024, defaults.init_width), 4);
  TrackerOptions narrow;
  narrow.init_width = 8;
  EXPECT_THROW(narrow.Check(), UsageError);
  SilhouetteFitOptions fit;
  fit.automatic_width = 0;
  EXPECT_THROW(fit.Check(), UsageError);
}

}  // namespace
}  // namespace confluent
