// The first frame's fit holds the body to human proportions, so a body whose head, shanks and
// upper arms differ from the average comes out average. With the later frames' masks the tracker
// learns the shape over the first frames (TrackerOptions::shape_samples). Ground truth: masks of
// the template itself in a known non-uniform shape, moving; a held-out camera scores the result.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "calib/rig_check.h"
#include "silhouette/overlap.h"
#include "tracking/tracker.h"
#include "tests/support/camera_ring.h"
#include "tests/support/template_masks.h"

namespace confluent {
namespace {

struct MovingBody {
  BodyTemplate body;
  BodyShape shape = BodyShape::Uniform(1.75);
  Rig rig = testing::CameraRing(9, 320, 240);  // the last camera is held out
  static constexpr int kFrames = 26;
  MovingBody() {
    shape.girth_scale[int(BodySegment::kHead)] *= 1.2;
    for (BodySegment s : {BodySegment::kLeftShank, BodySegment::kRightShank}) shape.girth_scale[int(s)] *= 0.8;
    for (BodySegment s : {BodySegment::kLeftUpperArm, BodySegment::kRightUpperArm}) shape.girth_scale[int(s)] *= 0.85;
    for (BodySegment s : {BodySegment::kLeftThigh, BodySegment::kRightThigh}) shape.girth_scale[int(s)] *= 1.1;
  }
  // Arms swinging out and back, a knee bending, the body turning.
  TemplatePose Pose(int frame) const {
    const double t = frame / double(kFrames - 1);
    TemplatePose pose;
    pose.root_rotation = Eigen::Vector3d(0, 0, 0.3 + 0.8 * t);
    pose.dofs[kJointLeftShoulder] = {0.0, 0.3 + 0.6 * std::sin(M_PI * t), 0.0};
    pose.dofs[kJointRightShoulder] = {0.4 * std::sin(M_PI * t), -0.3, 0.0};
    pose.dofs[kJointRightElbow] = {0.3 + 0.5 * t, 0.0, 0.0};
    pose.dofs[kJointLeftHip] = {0.5 * std::sin(M_PI * t), 0.0, 0.0};
    pose.dofs[kJointLeftKnee] = {-0.8 * std::sin(M_PI * t), 0.0, 0.0};
    return pose;
  }
  std::vector<Image> Masks(int frame) const { return testing::TemplateMasks(body, shape, Pose(frame), rig); }
};

struct ShapeLearningRun {
  TrackedFrame frame;
  BodyShape shape;
  double held_out_iou = 0.0;
  double girth_error = 0.0;  // mean over the segments, |fitted - true| girth scale
};

ShapeLearningRun InitialiseMovingBody(const MovingBody& scene, bool later_masks) {
  TrackerOptions options;
  options.fit.rest_prior_scale = 0.0;  // one first fit, not two
  options.try_skirt = false;
  options.limb_search = false;
  options.arm_twist_search = false;
  std::vector<bool> held_out(scene.rig.size(), false);
  held_out.back() = true;
  Tracker tracker(scene.rig, held_out, options);
  if (later_masks)
    tracker.UseLaterMasks([&](int frame) { return frame < MovingBody::kFrames ? scene.Masks(frame) : std::vector<Image>(); });
  ShapeLearningRun out;
  const std::vector<Image> masks = scene.Masks(0);
  out.frame = tracker.Initialize(0, masks);
  out.shape = tracker.shape();
  const Mesh mesh = tracker.body().PosedMesh(tracker.shape(), out.frame.pose);
  out.held_out_iou = MaskIoU(RasterizeClosedMesh(mesh, scene.rig.cameras.back()), masks.back());
  for (int s = 0; s < kNumBodySegments; ++s)
    out.girth_error += std::abs(out.shape.girth_scale[s] - scene.shape.girth_scale[s]) / kNumBodySegments;
  return out;
}

bool HasShapeFlag(const TrackedFrame& frame, const std::string& flag) {
  return std::find(frame.flags.begin(), frame.flags.end(), flag) != frame.flags.end();
}

TEST(ShapeLearning, TheFirstFramesTeachTheShapeThatTheFirstFitAverages) {
  const MovingBody scene;
  const ShapeLearningRun alone = InitialiseMovingBody(scene, false);
  const ShapeLearningRun learned = InitialiseMovingBody(scene, true);
  EXPECT_FALSE(HasShapeFlag(alone.frame, "shape:6"));
  EXPECT_TRUE(HasShapeFlag(learned.frame, "shape:6"));  // frames 0, 5, ..., 25
  // The learned girths are nearer the truth, segment by segment on average, and the held-out
  // camera sees the first frame better.
  EXPECT_LT(learned.girth_error, 0.6 * alone.girth_error) << alone.girth_error << " " << learned.girth_error;
  EXPECT_GT(learned.held_out_iou, alone.held_out_iou);
  EXPECT_GT(learned.shape.girth_scale[int(BodySegment::kHead)], alone.shape.girth_scale[int(BodySegment::kHead)]);
  EXPECT_LT(learned.shape.girth_scale[int(BodySegment::kLeftShank)], alone.shape.girth_scale[int(BodySegment::kLeftShank)]);
}

TEST(ShapeLearning, FewerLaterFramesGiveFewerSamples) {
  // Masks for frames 0-12 only: samples at 0, 5 and 10.
  const MovingBody scene;
  TrackerOptions options;
  options.fit.rest_prior_scale = 0.0;
  options.try_skirt = false;
  options.limb_search = false;
  options.arm_twist_search = false;
  Tracker tracker(scene.rig, {}, options);
  tracker.UseLaterMasks([&](int frame) { return frame <= 12 ? scene.Masks(frame) : std::vector<Image>(); });
  EXPECT_TRUE(HasShapeFlag(tracker.Initialize(0, scene.Masks(0)), "shape:3"));
  // The learned shape is the tracker's from the first frame on: the next frame continues from it.
  const BodyShape shape = tracker.shape();
  tracker.Track(1, scene.Masks(1));
  EXPECT_EQ(tracker.shape().girth_scale, shape.girth_scale);
}

}  // namespace
}  // namespace confluent
