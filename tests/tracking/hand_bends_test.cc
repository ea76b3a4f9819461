// An arm re-placed by the landmarks or the lost-limb search takes the hand that fits the
// silhouettes (HandBends in tracking/limb_hypotheses.h, TrackerOptions::hand_rebend_flex_deg).
// Ground truth: the template with its upper arms spread, the left forearm folded before the
// chest and the hand bent further in at the wrist (the Indian dance's pose), its own silhouettes,
// and landmarks that place the wrist 8 cm off, as BlazePose does there. The tracker holds the
// forearm elsewhere, the hand bent the other way.

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "tests/support/camera_ring.h"
#include "tests/support/template_masks.h"
#include "tracking/limb_hypotheses.h"
#include "tracking/tracker.h"

namespace confluent {
namespace {

constexpr double kRadPerDegree = M_PI / 180.0;

// Both upper arms spread sideways; the left elbow flexed `elbow_deg` (forwards, towards the
// chest) and the left wrist `wrist_deg` further.
TemplatePose ArmsSpreadLeftFolded(const BodyTemplate& body, double elbow_deg, double wrist_deg) {
  TemplatePose pose;
  pose.root_rotation = Eigen::Vector3d(0, 0, 0.3);
  pose.dofs[kJointLeftShoulder] = testing::ArmTowards(body, kJointLeftShoulder, Eigen::Vector3d(-1, 0, -0.1));
  pose.dofs[kJointRightShoulder] = testing::ArmTowards(body, kJointRightShoulder, Eigen::Vector3d(1, 0, -0.1));
  pose.dofs[kJointLeftElbow] = {elbow_deg * kRadPerDegree, 0, 0};
  pose.dofs[kJointLeftWrist] = {wrist_deg * kRadPerDegree, 0, 0};
  return pose;
}

TEST(HandBends, BendTheHandAtTheWristAndNothingElse) {
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.75);
  TemplatePose pose = ArmsSpreadLeftFolded(body, 100, 0);
  pose.dofs[kJointLeftWrist][1] = 0.2;  // bent sideways too
  const std::vector<Eigen::Vector3d> joints = body.JointPositions(shape, pose);
  const std::vector<TemplatePose> bent = HandBends(body, pose, Limb::kLeftArm, {-40, 0, 40, 120});
  ASSERT_EQ(bent.size(), 4u);
  const JointDof& wrist = body.dofs()[kJointLeftWrist];
  EXPECT_NEAR(bent[0].dofs[kJointLeftWrist][0], -40 * kRadPerDegree, 1e-12);
  EXPECT_NEAR(bent[2].dofs[kJointLeftWrist][0], 40 * kRadPerDegree, 1e-12);
  EXPECT_NEAR(bent[3].dofs[kJointLeftWrist][0], wrist.upper[0], 1e-12);  // within the limits
  for (const TemplatePose& hypothesis : bent) {
    EXPECT_EQ(hypothesis.dofs[kJointLeftWrist][1], 0.0);  // no sideways bend
    const std::vector<Eigen::Vector3d> moved = body.JointPositions(shape, hypothesis);
    for (int j = 0; j < kNumTemplateJoints; ++j) {
      if (j == kJointLeftHandEnd) continue;
      EXPECT_LT((moved[j] - joints[j]).norm(), 1e-12) << BodyJointNames()[j];
    }
  }
  // The straight hand continues the forearm; 40 degrees of flexion turn it by 40.
  const std::vector<Eigen::Vector3d> straight = body.JointPositions(shape, bent[1]);
  const std::vector<Eigen::Vector3d> flexed = body.JointPositions(shape, bent[2]);
  const Eigen::Vector3d forearm = (straight[kJointLeftWrist] - straight[kJointLeftElbow]).normalized();
  const Eigen::Vector3d hand = (flexed[kJointLeftHandEnd] - flexed[kJointLeftWrist]).normalized();
  EXPECT_NEAR((straight[kJointLeftHandEnd] - straight[kJointLeftWrist]).normalized().dot(forearm), 1.0, 1e-9);
  EXPECT_NEAR(std::acos(hand.dot(forearm)), 40 * kRadPerDegree, 1e-6);
  EXPECT_TRUE(HandBends(body, pose, Limb::kLeftLeg, {0, 40}).empty());
}

// Eight cameras see the template with the left forearm folded 105 degrees and the hand bent 60
// degrees further in.
struct FoldedHandScene {
  BodyTemplate body;
  BodyShape shape = BodyShape::Uniform(1.75);
  Rig rig = testing::CameraRing(8, 200, 150);
  TemplatePose truth = ArmsSpreadLeftFolded(body, 105, 60);
  std::vector<Image> masks = testing::TemplateMasks(body, shape, truth, rig);
  Eigen::Vector3d true_wrist = body.JointPositions(shape, truth)[kJointLeftWrist];

  // The left wrist's distance from the truth after `options`' tracker, resumed from `held` with
  // `iou_history`, tracks `frame` (with `landmarks` when given); the frame's flags go to `flags`.
  double TrackedWristError(const TrackerOptions& options, const TemplatePose& held, double iou_history, int frame,
                           const std::shared_ptr<const LandmarkJoints>& landmarks, std::string* flags) const {
    Tracker tracker(rig, {}, options);
    if (landmarks) tracker.UseLandmarks([&](int) { return landmarks; });
    tracker.Resume(shape, {held, held}, std::vector<double>(10, iou_history), {});
    const TrackedFrame result = tracker.Track(frame, masks);
    for (const std::string& flag : result.flags) *flags += flag + " ";
    return (result.joints[kJointLeftWrist] - true_wrist).norm();
  }
};

// The truth: the left forearm folded 105 degrees, the hand bent 60 degrees further in. The
// tracker held the forearm straight out or folded 150 degrees, the hand bent 60 degrees out.
// Turned onto the landmarks' wrist with the hand it had, the hand points out of the silhouettes
// and the fit folds the forearm away again; with the hand bent as the silhouettes say, the fit
// finds the true wrist.
TEST(HandBends, AForearmTurnedOntoMisplacedLandmarksFindsTheTrueWristWithItsHand) {
  const FoldedHandScene scene;
  const BodyTemplate& body = scene.body;
  const BodyShape& shape = scene.shape;
  LandmarkJoints landmarks = testing::TemplateLandmarks(body, shape, scene.truth);
  // Misplaced towards the elbow and up, 8 cm.
  landmarks.position[kJointLeftWrist] += 0.08 * Eigen::Vector3d(-0.6, -0.6, 0.5).normalized();
  const auto shared_landmarks = std::make_shared<const LandmarkJoints>(landmarks);
  auto track = [&](const TemplatePose& held, const std::vector<double>& flex_deg, std::string* flags) {
    TrackerOptions options;
    options.hand_rebend_flex_deg = flex_deg;
    // No overlap to drop from (IoU history 0); frame 10 is a landmark check.
    return scene.TrackedWristError(options, held, 0.0, 10, shared_landmarks, flags);
  };
  for (const TemplatePose& held : {ArmsSpreadLeftFolded(body, 0, -60), ArmsSpreadLeftFolded(body, 150, -60)}) {
    std::string with_flags, without_flags;
    EXPECT_LT(track(held, TrackerOptions{}.hand_rebend_flex_deg, &with_flags), 0.02) << with_flags;
    EXPECT_NE(with_flags.find("landmarks:left_arm"), std::string::npos) << with_flags;
    EXPECT_GT(track(held, {}, &without_flags), 0.1) << without_flags;
  }
  // A hand bent less than hand_rebend_min_rad (45 degrees) keeps its bend: the same
  // frame as without the bends.
  std::string a, b;
  const TemplatePose slightly_bent = ArmsSpreadLeftFolded(body, 150, -20);
  EXPECT_DOUBLE_EQ(track(slightly_bent, TrackerOptions{}.hand_rebend_flex_deg, &a), track(slightly_bent, {}, &b));
  EXPECT_EQ(a, b);
}

// The same without landmarks: the frame's overlap falls below the frames before, and the
// lost-limb search's canonical placements (arm spread, forearm bent 90 degrees) find the fold
// only with the hand re-bent.
TEST(HandBends, TheLostLimbSearchFindsTheFoldedForearmWithItsHand) {
  const FoldedHandScene scene;
  const BodyTemplate& body = scene.body;
  auto track = [&](const TemplatePose& held, const std::vector<double>& flex_deg, std::string* flags) {
    TrackerOptions options;
    options.hand_rebend_flex_deg = flex_deg;
    // The template's own silhouettes: the wrong forearm still overlaps 0.983-0.985, so the frames
    // before were explained fully and a smaller drop sets the search off.
    options.limb_search_drop = 0.005;
    return scene.TrackedWristError(options, held, 1.0, 11, nullptr, flags);
  };
  for (const TemplatePose& held : {ArmsSpreadLeftFolded(body, 0, -60), ArmsSpreadLeftFolded(body, 150, -60)}) {
    std::string with_flags, without_flags;
    EXPECT_LT(track(held, TrackerOptions{}.hand_rebend_flex_deg, &with_flags), 0.02) << with_flags;
    EXPECT_NE(with_flags.find("limb:left_arm"), std::string::npos) << with_flags;
    EXPECT_GT(track(held, {}, &without_flags), 0.1) << without_flags;
  }
}

}  // namespace
}  // namespace confluent
