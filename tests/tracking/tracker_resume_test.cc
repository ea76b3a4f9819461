// A resumed tracker (Tracker::ResumeAfter, as `confluent run` resumes from the tracking state
// files) tracks as the uninterrupted one, also across a repeated frame, which Track skips: its
// pose is not history, its overlap not part of the lost-limb windows.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "silhouette/overlap.h"
#include "tracking/tracker.h"
#include "tests/support/camera_ring.h"
#include "tests/support/template_masks.h"

namespace confluent {
namespace {

// The performer turns and raises the left arm; frame 6 repeats frame 5 (a dropped frame that
// the recorder filled with the one before), in the middle of the motion.
std::vector<TemplatePose> RaiseWithARepeat() {
  std::vector<TemplatePose> poses;
  for (int f = 0; f < 10; ++f) {
    const int t = f <= 5 ? f : f - 1;
    TemplatePose pose;
    pose.root_translation = Eigen::Vector3d(0.02 * t, 0.0, 0.0);
    pose.root_rotation = Eigen::Vector3d(0, 0, 0.3 + 0.06 * t);
    pose.dofs[kJointLeftShoulder] = {0.0, 0.12 * t, 0.0};
    pose.dofs[kJointLeftElbow] = {0.1 * t, 0.0, 0.0};
    poses.push_back(pose);
  }
  return poses;
}

bool HasFlag(const TrackedFrame& frame, const std::string& flag) {
  return std::find(frame.flags.begin(), frame.flags.end(), flag) != frame.flags.end();
}

double WorstJointDifference(const TrackedFrame& a, const TrackedFrame& b) {
  double worst = 0.0;
  for (std::size_t j = 0; j < a.joints.size(); ++j) worst = std::max(worst, (a.joints[j] - b.joints[j]).norm());
  return worst;
}

TEST(TrackerResume, AResumedRunTracksAsTheUninterruptedOneAcrossARepeatedFrame) {
  const BodyTemplate body;
  const BodyShape truth_shape = BodyShape::Uniform(1.75);
  const Rig rig = testing::CameraRing(8, 320, 240);
  std::vector<std::vector<Image>> masks;
  for (const TemplatePose& pose : RaiseWithARepeat()) masks.push_back(testing::TemplateMasks(body, truth_shape, pose, rig));
  const int frames = static_cast<int>(masks.size());

  Tracker uninterrupted(rig, {});
  std::vector<TrackedFrame> tracked;
  for (int f = 0; f < frames; ++f)
    tracked.push_back(f == 0 ? uninterrupted.Initialize(f, masks[f]) : uninterrupted.Track(f, masks[f]));
  ASSERT_TRUE(HasFlag(tracked[6], "duplicate"));
  ASSERT_FALSE(HasFlag(tracked[7], "duplicate"));

  // Resumed at every frame after the first: the frames before as their state files hold them.
  for (int resume = 1; resume < frames; ++resume) {
    Tracker resumed(rig, {});
    resumed.ResumeAfter(uninterrupted.shape(),
                        std::vector<TrackedFrame>(tracked.begin(), tracked.begin() + resume), masks[resume - 1]);
    for (int f = resume; f < frames; ++f) {
      const TrackedFrame result = resumed.Track(f, masks[f]);
      EXPECT_EQ(HasFlag(result, "duplicate"), HasFlag(tracked[f], "duplicate")) << "resumed at " << resume << ", frame " << f;
      EXPECT_LT(WorstJointDifference(result, tracked[f]), 1e-6) << "resumed at " << resume << ", frame " << f;
      EXPECT_DOUBLE_EQ(result.mean_iou, tracked[f].mean_iou) << "resumed at " << resume << ", frame " << f;
    }
  }
}

TEST(TrackerResume, ResumingWithoutATrackedFrameIsRefused) {
  Tracker tracker(testing::CameraRing(4, 160, 120), {});
  EXPECT_THROW(tracker.ResumeAfter(BodyShape::Uniform(1.75), {}, {}), std::invalid_argument);
  TrackedFrame repeat;
  repeat.flags = {"duplicate"};
  EXPECT_THROW(tracker.ResumeAfter(BodyShape::Uniform(1.75), {repeat}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace confluent
