// Limbs settled by triangulated landmarks (tracking/landmark_limbs.h, Tracker::UseLandmarks).
// Ground truth: masks rendered from the template itself, made ambiguous on purpose (the union
// of the body with its left forearm folded two ways), and landmark joints taken from one of the
// two poses: the tracker must follow whichever the landmarks say.

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "tests/support/camera_ring.h"
#include "tests/support/template_masks.h"
#include "tracking/landmark_limbs.h"
#include "tracking/tracker.h"

namespace confluent {
namespace {

// The left upper arm raised forwards, the elbow bent 80 degrees; the upper arm's twist about
// its own axis turns the fold (the elbow stays where it is): `inwards` across the chest, else
// 80 degrees further round.
TemplatePose ForearmFolded(const BodyTemplate& body, bool inwards) {
  TemplatePose pose;
  pose.root_rotation = Eigen::Vector3d(0, 0, 0.3);
  const Eigen::AngleAxisd raised(1.2, -Eigen::Vector3d::UnitX());
  const Eigen::Vector3d upper_arm =
      raised * (body.generic_rest()[kJointLeftElbow] - body.generic_rest()[kJointLeftShoulder]).normalized();
  const Eigen::AngleAxisd shoulder(Eigen::AngleAxisd(inwards ? 0.0 : 1.4, upper_arm) * raised);
  const Eigen::Vector3d r = shoulder.angle() * shoulder.axis();
  pose.dofs[kJointLeftShoulder] = {r.x(), r.y(), r.z()};
  pose.dofs[kJointLeftElbow] = {1.4, 0, 0};
  return pose;
}

// A skirt to the ankles hides the legs from the landmarks (the real Tsinghua frame's fitted skirt
// on its 1.49 m performer: 0.69 m, flaring 0.12 m); a knee-length one does not (samba's: 0.45 m
// on a 1.72 m performer).
TEST(LandmarkLimbs, OnlyASkirtBelowTheAnkleHidesTheLeg) {
  const BodyTemplate body;
  const TemplatePose standing;
  BodyShape shape = BodyShape::Uniform(1.49);
  for (Limb limb : kAllLimbs) EXPECT_FALSE(SkirtHidesAnkle(body, shape, standing, limb)) << LimbName(limb);
  shape.skirt_length_m = 0.69;
  shape.skirt_flare_m = 0.12;
  EXPECT_TRUE(SkirtHidesAnkle(body, shape, standing, Limb::kLeftLeg));
  EXPECT_TRUE(SkirtHidesAnkle(body, shape, standing, Limb::kRightLeg));
  EXPECT_FALSE(SkirtHidesAnkle(body, shape, standing, Limb::kLeftArm));
  EXPECT_FALSE(SkirtHidesAnkle(body, shape, standing, Limb::kRightArm));
  shape = BodyShape::Uniform(1.72);
  shape.skirt_length_m = 0.45;
  EXPECT_FALSE(SkirtHidesAnkle(body, shape, standing, Limb::kLeftLeg));
  EXPECT_FALSE(SkirtHidesAnkle(body, shape, standing, Limb::kRightLeg));
}

TEST(LandmarkLimbs, TheLowerBoneTurnsOntoTheLandmarksWristTheRestStays) {
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.75);
  const TemplatePose from = ForearmFolded(body, true), to = ForearmFolded(body, false);
  const std::vector<Eigen::Vector3d> target = body.JointPositions(shape, to);
  const std::vector<Eigen::Vector3d> start = body.JointPositions(shape, from);
  EXPECT_LT((target[kJointLeftElbow] - start[kJointLeftElbow]).norm(), 0.01);
  EXPECT_GT((target[kJointLeftWrist] - start[kJointLeftWrist]).norm(), 0.2);
  const std::vector<TemplatePose> hypotheses =
      LimbsFromLandmarks(body, shape, from, Limb::kLeftArm, testing::TemplateLandmarks(body, shape, to));
  ASSERT_EQ(hypotheses.size(), 2u);  // the forearm alone, both bones
  for (const TemplatePose& hypothesis : hypotheses) {
    const std::vector<Eigen::Vector3d> joints = body.JointPositions(shape, hypothesis);
    EXPECT_LT((joints[kJointLeftWrist] - target[kJointLeftWrist]).norm(), 0.03);
    for (int j : {kJointRightWrist, kJointLeftAnkle, kJointRightAnkle, kJointHead})
      EXPECT_LT((joints[j] - start[j]).norm(), 0.01) << BodyJointNames()[j];
  }
  EXPECT_LT(LimbDisagreement(body.JointPositions(shape, hypotheses[0]), testing::TemplateLandmarks(body, shape, to),
                             Limb::kLeftArm),
            0.03);
  LandmarkJoints unknown = testing::TemplateLandmarks(body, shape, to);
  unknown.cameras[kJointLeftWrist] = 0;
  EXPECT_TRUE(LimbsFromLandmarks(body, shape, from, Limb::kLeftArm, unknown).empty());
  EXPECT_LT(LimbDisagreement(start, unknown, Limb::kLeftArm), 0.0);
}

// Overlap is given up for landmarks only as far as they disagree: nothing at the threshold,
// the full tolerance from landmark_full_tolerance_m on, linearly between.
TEST(LandmarkLimbs, TheOverlapGivenUpGrowsWithTheDisagreement) {
  TrackerOptions options;
  options.landmark_disagreement_m = 0.08;
  options.landmark_full_tolerance_m = 0.16;
  options.landmark_iou_tolerance = 0.015;
  EXPECT_DOUBLE_EQ(LandmarkIouTolerance(options, 0.08), 0.0);
  EXPECT_NEAR(LandmarkIouTolerance(options, 0.10), 0.00375, 1e-12);
  EXPECT_NEAR(LandmarkIouTolerance(options, 0.12), 0.0075, 1e-12);
  EXPECT_DOUBLE_EQ(LandmarkIouTolerance(options, 0.16), 0.015);
  EXPECT_DOUBLE_EQ(LandmarkIouTolerance(options, 0.40), 0.015);
  options.landmark_full_tolerance_m = 0.0;
  EXPECT_THROW(options.Check(), UsageError);
}

// Eight cameras see the union of the body with its left forearm folded both ways.
struct FoldScene {
  BodyTemplate body;
  BodyShape shape = BodyShape::Uniform(1.75);
  Rig rig = testing::CameraRing(8, 200, 150);
  TemplatePose inwards = ForearmFolded(body, true), up = ForearmFolded(body, false);
  std::vector<Image> masks = testing::UnionTemplateMasks(body, shape, inwards, up, rig);
};

// The tracker holds the forearm one way when a frame's overlap drops (the masks hold both
// folds); the landmarks say which: the tracker follows them, either way round.
TEST(LandmarkLimbs, TheTrackerFollowsTheLandmarksWhereTheSilhouettesHoldBothFolds) {
  const FoldScene scene;
  const BodyTemplate& body = scene.body;
  const BodyShape& shape = scene.shape;
  const Rig& rig = scene.rig;
  const TemplatePose &inwards = scene.inwards, &up = scene.up;
  const std::vector<Image>& masks = scene.masks;
  auto left_wrist_error = [&](const TemplatePose& held, const TemplatePose& said, std::string* flags) {
    TrackerOptions options;
    Tracker tracker(rig, {}, options);
    const LandmarkJoints landmarks = testing::TemplateLandmarks(body, shape, said);
    tracker.UseLandmarks([&](int) { return std::make_shared<const LandmarkJoints>(landmarks); });
    tracker.Resume(shape, {held, held}, std::vector<double>(10, 0.99), {});  // the frames before were explained
    const TrackedFrame result = tracker.Track(10, masks);
    for (const std::string& flag : result.flags) *flags += flag + " ";
    return (result.joints[kJointLeftWrist] - body.JointPositions(shape, said)[kJointLeftWrist]).norm();
  };
  std::string flags_up, flags_inwards;
  EXPECT_LT(left_wrist_error(inwards, up, &flags_up), 0.05) << flags_up;
  EXPECT_NE(flags_up.find("landmarks:left_arm"), std::string::npos) << flags_up;
  EXPECT_LT(left_wrist_error(up, inwards, &flags_inwards), 0.05) << flags_inwards;
  EXPECT_NE(flags_inwards.find("landmarks:left_arm"), std::string::npos) << flags_inwards;
  // Without a landmark source the tracker keeps the fold it held: the silhouettes do not decide.
  Tracker plain(rig, {}, TrackerOptions{});
  plain.Resume(shape, {inwards, inwards}, std::vector<double>(10, 0.99), {});
  const TrackedFrame kept = plain.Track(10, masks);
  EXPECT_GT((kept.joints[kJointLeftWrist] - body.JointPositions(shape, up)[kJointLeftWrist]).norm(), 0.15);
}

// A forearm held the wrong way while the overlap does not drop (no lost-limb search): the
// landmarks asked every TrackerOptions::landmark_check_every frames still turn it, in those
// frames only.
TEST(LandmarkLimbs, TheTrackerAsksTheLandmarksEveryFewFramesWithoutAnOverlapDrop) {
  const FoldScene scene;
  const LandmarkJoints landmarks = testing::TemplateLandmarks(scene.body, scene.shape, scene.up);
  auto left_wrist_error = [&](int every, int frame, int* asked) {
    TrackerOptions options;
    options.landmark_check_every = every;
    Tracker tracker(scene.rig, {}, options);
    tracker.UseLandmarks([&](int) {
      ++*asked;
      return std::make_shared<const LandmarkJoints>(landmarks);
    });
    tracker.Resume(scene.shape, {scene.inwards, scene.inwards}, std::vector<double>(10, 0.0), {});  // nothing to drop from
    const TrackedFrame result = tracker.Track(frame, scene.masks);
    return (result.joints[kJointLeftWrist] - scene.body.JointPositions(scene.shape, scene.up)[kJointLeftWrist]).norm();
  };
  int asked = 0;
  EXPECT_LT(left_wrist_error(5, 10, &asked), 0.05);
  EXPECT_EQ(asked, 1);
  asked = 0;
  EXPECT_GT(left_wrist_error(5, 11, &asked), 0.15);
  EXPECT_EQ(asked, 0);
  EXPECT_GT(left_wrist_error(0, 10, &asked), 0.15);
  EXPECT_EQ(asked, 0);
}

}  // namespace
}  // namespace confluent
