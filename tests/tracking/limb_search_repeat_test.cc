// A lost-limb search that keeps the pose is not run again on the frames after it while they are no
// worse (TrackerOptions::limb_search_repeat_drop), and runs again, and finds the limb, on a frame
// that is. Ground truth: the template's own silhouettes, with a patch in every camera's corner
// that no limb can reach (so the overlap stays below what the frames before showed).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tracking/motion_io.h"
#include "tracking/tracker.h"
#include "tests/support/camera_ring.h"
#include "tests/support/template_masks.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

// The template's masks in `pose` with a `size` x `size` px patch in each image's top left corner.
std::vector<Image> MasksWithCornerPatch(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& pose,
                                        const Rig& rig, int size) {
  std::vector<Image> masks = testing::TemplateMasks(body, shape, pose, rig);
  for (Image& mask : masks)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) mask.at<std::uint8_t>(x, y) = 255;
  return masks;
}

// Arms down, the left one folded across the chest; `forward`: the left arm reaches forward
// instead (front cameras see it inside the torso, so the frame-to-frame fit keeps the fold).
TemplatePose ArmPose(const BodyTemplate& body, bool forward, double shift_m) {
  TemplatePose pose;
  pose.root_translation = Eigen::Vector3d(shift_m, 0.0, 0.0);
  pose.root_rotation = Eigen::Vector3d(0, 0, 0.3);
  if (!forward) return testing::WithLeftArmFolded(body, pose);
  pose.dofs[kJointLeftShoulder] = testing::ArmTowards(body, kJointLeftShoulder, Eigen::Vector3d(-0.1, 1.0, 0.0));
  return pose;
}

bool HasLimbSearchFlag(const TrackedFrame& frame) {
  return std::any_of(frame.flags.begin(), frame.flags.end(),
                     [](const std::string& flag) { return flag.rfind("limb:", 0) == 0; });
}

struct PatchedScene {
  BodyTemplate body;
  BodyShape shape = BodyShape::Uniform(1.75);
  Rig rig = testing::CameraRing(8, 320, 240);
  TemplatePose folded = ArmPose(body, false, 0.0);
  // The overlap of the clean frames before: the patch makes every frame here fall below it.
  std::vector<double> ious_before = std::vector<double>(10, 0.97);
};

TrackerOptions WithoutLandmarkChecks() {
  TrackerOptions options;
  options.landmark_check_every = 0;
  return options;
}

TEST(LimbSearchRepeat, AFruitlessSearchIsNotRepeatedUntilAFrameIsWorse) {
  const PatchedScene scene;
  Tracker tracker(scene.rig, {}, WithoutLandmarkChecks());
  tracker.Resume(scene.shape, {scene.folded, scene.folded}, scene.ious_before, {});
  // Frame 10: the patch lowers the overlap, the search runs and finds nothing to move.
  const TrackedFrame first = tracker.Track(10, MasksWithCornerPatch(scene.body, scene.shape, scene.folded, scene.rig, 40));
  ASSERT_LT(first.mean_iou, 0.95);
  EXPECT_EQ(first.limb_search, LimbSearch::kRan);
  EXPECT_FALSE(HasLimbSearchFlag(first));
  ASSERT_TRUE(first.fruitless_search.pending());
  EXPECT_EQ(first.fruitless_search.mean_iou, first.mean_iou);
  EXPECT_EQ(first.fruitless_search.mean_contour_px, first.fit.mean_contour_px);
  // Frame 11: the performer moved 3 mm, the frame is as good as frame 10: not searched again.
  const PatchedScene& s = scene;
  const TrackedFrame second = tracker.Track(11, MasksWithCornerPatch(s.body, s.shape, ArmPose(s.body, false, 0.003), s.rig, 40));
  EXPECT_EQ(second.limb_search, LimbSearch::kSkipped);
  EXPECT_NEAR(second.mean_iou, first.mean_iou, 0.01);
  EXPECT_EQ(second.fruitless_search.mean_iou, first.mean_iou);
  // Frame 12: the left arm reaches forward, unexplained: worse than frame 10, so the search runs
  // again and places the arm.
  const TemplatePose forward = ArmPose(s.body, true, 0.003);
  const TrackedFrame third = tracker.Track(12, MasksWithCornerPatch(s.body, s.shape, forward, s.rig, 40));
  EXPECT_EQ(third.limb_search, LimbSearch::kRan);
  EXPECT_TRUE(HasLimbSearchFlag(third));
  EXPECT_FALSE(third.fruitless_search.pending());
  const int wrist = kJointLeftWrist;
  EXPECT_LT((s.body.JointPositions(s.shape, forward)[wrist] - third.joints[wrist]).norm(), 0.05);
  // Frame 13: the patch is gone, the frame no longer triggers a search.
  const TrackedFrame clean = tracker.Track(13, testing::TemplateMasks(s.body, s.shape, ArmPose(s.body, true, 0.0), s.rig));
  EXPECT_EQ(clean.limb_search, LimbSearch::kNotTriggered);
  EXPECT_FALSE(clean.fruitless_search.pending());
}

// Frame 11 with a bigger patch: its overlap falls more than limb_search_repeat_drop below frame
// 10's, so the search runs again.
TEST(LimbSearchRepeat, AWorseFrameBeyondTheMarginsIsSearchedAgain) {
  const PatchedScene scene;
  TrackerOptions options = WithoutLandmarkChecks();
  Tracker tracker(scene.rig, {}, options);
  tracker.Resume(scene.shape, {scene.folded, scene.folded}, scene.ious_before, {});
  const TrackedFrame first =
      tracker.Track(10, MasksWithCornerPatch(scene.body, scene.shape, scene.folded, scene.rig, 40));
  ASSERT_EQ(first.limb_search, LimbSearch::kRan);
  // A bigger patch: the overlap falls further than limb_search_repeat_drop below frame 10's.
  const TrackedFrame second = tracker.Track(
      11, MasksWithCornerPatch(scene.body, scene.shape, ArmPose(scene.body, false, 0.003), scene.rig, 60));
  ASSERT_LT(second.mean_iou, first.mean_iou - options.limb_search_repeat_drop);
  EXPECT_EQ(second.limb_search, LimbSearch::kRan);
}

// The pending search survives the tracking state files: a run resumed after frame 10 skips
// frame 11 as the uninterrupted one did.
TEST(LimbSearchRepeat, AResumedRunKnowsTheFruitlessSearch) {
  const PatchedScene scene;
  const std::vector<Image> masks10 = MasksWithCornerPatch(scene.body, scene.shape, scene.folded, scene.rig, 40);
  const std::vector<Image> masks11 =
      MasksWithCornerPatch(scene.body, scene.shape, ArmPose(scene.body, false, 0.003), scene.rig, 40);
  TrackedFrame clean;  // the frames before, as their state files hold them
  clean.pose = scene.folded;
  clean.mean_iou = 0.97;
  std::vector<TrackedFrame> state(9, clean);
  for (int f = 0; f < 9; ++f) state[f].frame = f + 1;

  Tracker uninterrupted(scene.rig, {}, WithoutLandmarkChecks());
  uninterrupted.ResumeAfter(scene.shape, state, {});
  const TrackedFrame frame10 = uninterrupted.Track(10, masks10);
  ASSERT_EQ(frame10.limb_search, LimbSearch::kRan);
  const TrackedFrame expected = uninterrupted.Track(11, masks11);
  ASSERT_EQ(expected.limb_search, LimbSearch::kSkipped);

  testing::TempDir dir;
  const std::string path = dir / "000010.json";
  WritePosesJson(path, scene.body, scene.shape, {}, {frame10}, 25.0);
  state.push_back(ReadPosesJson(path, scene.body, {}).frames.at(0));
  Tracker resumed(scene.rig, {}, WithoutLandmarkChecks());
  resumed.ResumeAfter(scene.shape, state, masks10);
  const TrackedFrame result = resumed.Track(11, masks11);
  EXPECT_EQ(result.limb_search, LimbSearch::kSkipped);
  EXPECT_NEAR(result.mean_iou, expected.mean_iou, 1e-6);
}

}  // namespace
}  // namespace confluent
