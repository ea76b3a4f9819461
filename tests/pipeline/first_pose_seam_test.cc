// The first frames of a scan in the first tracked frame's pose ease from the registered pose into
// the tracked ones: the registered pose at frame 0, the tracked poses from the seam's end, and a
// correction that shrinks in between.

#include "pipeline/first_pose_seam.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>

namespace confluent {
namespace {

// A registered pose that differs from the first tracked one at the root, in a ball joint (the
// right shoulder) and in a hinge (the right elbow), and a later tracked pose that moved on.
struct SeamCase {
  BodyTemplate body;
  BodyShape shape = BodyShape::Uniform(1.75);
  FirstPoseSeam seam;
  TemplatePose later;
  SeamCase() {
    seam.first_tracked.root_translation = {0.1, -0.2, 0.05};
    seam.first_tracked.root_rotation = {0.0, 0.0, 0.4};
    seam.first_tracked.dofs[kJointRightShoulder] = {0.2, -0.5, 0.1};
    seam.first_tracked.dofs[kJointRightElbow][0] = 1.0;
    seam.registered = seam.first_tracked;
    seam.registered.root_translation += Eigen::Vector3d(0.01, 0.02, -0.01);
    seam.registered.root_rotation = {0.05, 0.0, 0.45};
    seam.registered.dofs[kJointRightShoulder] = {0.1, -0.6, 0.3};
    seam.registered.dofs[kJointRightElbow][0] = 0.6;
    seam.frames = 10;
    later = seam.first_tracked;
    later.root_translation += Eigen::Vector3d(0.3, 0.0, 0.0);
    later.dofs[kJointRightShoulder] = {-0.4, -1.2, 0.0};
    later.dofs[kJointRightElbow][0] = 1.4;
  }
  // How far the pose's posed template is from `other`'s (largest vertex distance, m).
  double Distance(const TemplatePose& a, const TemplatePose& b) const {
    return (body.PosedMesh(shape, a).vertices - body.PosedMesh(shape, b).vertices).rowwise().norm().maxCoeff();
  }
};

TEST(FirstPoseSeam, FrameZeroTakesTheRegisteredPose) {
  const SeamCase c;
  EXPECT_LT(c.Distance(FirstPoseSeamPose(c.body, c.seam, c.seam.first_tracked, 0), c.seam.registered), 1e-9);
  EXPECT_GT(c.Distance(c.seam.first_tracked, c.seam.registered), 0.05);  // the case is not trivial
}

TEST(FirstPoseSeam, FramesFromTheSeamsEndAreTheTrackedOnes) {
  const SeamCase c;
  for (int frame : {10, 11, 50}) {
    const TemplatePose pose = FirstPoseSeamPose(c.body, c.seam, c.later, frame);
    EXPECT_EQ(c.Distance(pose, c.later), 0.0) << frame;
    RowMatrixX3d vertices = c.body.PosedMesh(c.shape, c.later).vertices;
    const RowMatrixX3d before = vertices;
    ApplyFirstPoseSeam(c.body, c.shape, c.seam, c.later, frame, &vertices);
    EXPECT_EQ((vertices - before).cwiseAbs().maxCoeff(), 0.0) << frame;
  }
}

TEST(FirstPoseSeam, TheCorrectionShrinksAcrossTheSeam) {
  const SeamCase c;
  EXPECT_DOUBLE_EQ(FirstPoseSeamWeight(c.seam, 0), 1.0);
  EXPECT_NEAR(FirstPoseSeamWeight(c.seam, 5), 0.5, 1e-12);
  double previous_weight = 1.0, previous_distance = 1e9;
  for (int frame = 1; frame < c.seam.frames; ++frame) {
    const double weight = FirstPoseSeamWeight(c.seam, frame);
    EXPECT_LT(weight, previous_weight);
    EXPECT_GT(weight, 0.0);
    // The later pose moved by this share of the correction: as far from the later pose as the
    // correction's share of the way from first tracked to registered.
    const double distance = c.Distance(FirstPoseSeamPose(c.body, c.seam, c.later, frame), c.later);
    EXPECT_LT(distance, previous_distance) << frame;
    EXPECT_GT(distance, 0.0) << frame;
    previous_weight = weight, previous_distance = distance;
  }
}

TEST(FirstPoseSeam, ApplyMovesTheTrackedTemplateToTheEasedPose) {
  const SeamCase c;
  for (int frame : {0, 3, 7}) {
    RowMatrixX3d vertices = c.body.PosedMesh(c.shape, c.later).vertices;
    ApplyFirstPoseSeam(c.body, c.shape, c.seam, c.later, frame, &vertices);
    const RowMatrixX3d expected = c.body.PosedMesh(c.shape, FirstPoseSeamPose(c.body, c.seam, c.later, frame)).vertices;
    EXPECT_LT((vertices - expected).cwiseAbs().maxCoeff(), 1e-12) << frame;
  }
}

// The silhouettes of frames 1..9 seen by a tracker that kept its frame-0 error until `found` (the
// corrected pose is the truth before it, the tracked one from it on): the seam ends there.
TEST(FirstPoseSeam, EndsWhereTheTrackedPoseExplainsTheSilhouettesBetter) {
  SeamCase c;
  auto tracked = [&](int) { return &c.later; };
  for (int found : {1, 4, 10}) {
    auto overlap = [&](int frame, const TemplatePose& pose) -> std::optional<double> {
      const TemplatePose truth = frame < found ? FirstPoseSeamPose(c.body, c.seam, c.later, frame) : c.later;
      return 1.0 - c.Distance(pose, truth);  // higher for the pose nearer the truth
    };
    c.seam.tracked_from = FirstPoseSeamEnd(c.body, c.seam, tracked, overlap);
    EXPECT_EQ(c.seam.tracked_from, found);
    EXPECT_DOUBLE_EQ(FirstPoseSeamWeight(c.seam, 0), 1.0);
    for (int frame = 1; frame < c.seam.frames; ++frame)
      EXPECT_EQ(FirstPoseSeamWeight(c.seam, frame) > 0.0, frame < found) << found << " " << frame;
    c.seam.tracked_from = std::numeric_limits<int>::max();
  }
  // Where a frame is not tracked, or its silhouettes are unknown, the search stops: the seam eases
  // as planned.
  auto always_tracked_better = [&](int, const TemplatePose& pose) -> std::optional<double> {
    return 1.0 - c.Distance(pose, c.later);
  };
  EXPECT_EQ(FirstPoseSeamEnd(c.body, c.seam, [&](int frame) { return frame < 3 ? nullptr : &c.later; },
                             always_tracked_better),
            c.seam.frames);
  EXPECT_EQ(FirstPoseSeamEnd(c.body, c.seam, tracked,
                             [&](int frame, const TemplatePose& pose) -> std::optional<double> {
                               if (frame == 1) return std::nullopt;
                               return always_tracked_better(frame, pose);
                             }),
            c.seam.frames);
}

TEST(FirstPoseSeam, LastsFourTenthsOfASecondAndAtLeastTwoFrames) {
  EXPECT_EQ(FirstPoseSeamFrames(25.0), 10);
  EXPECT_EQ(FirstPoseSeamFrames(60.0), 24);
  EXPECT_EQ(FirstPoseSeamFrames(2.5), 2);
}

}  // namespace
}  // namespace confluent
