// poses.json round trip of what `confluent track` reports per frame from it: the fit summary,
// the wall-clock and CPU seconds, the flags and the per-camera overlap.
#include "tracking/motion_io.h"

#include <gtest/gtest.h>

#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(PosesJson, PerFrameFitAndTimesRoundTrip) {
  const BodyTemplate body;
  TrackedFrame frame;
  frame.frame = 7;
  frame.camera_iou = {0.91, -1.0, 0.87};
  frame.mean_iou = 0.89;
  frame.flags = {"recovered"};
  frame.seconds = 0.42;
  frame.cpu_seconds = 0.81;
  frame.fit.iterations = 23;
  frame.fit.mean_outside_px = 0.37;
  frame.fit.mean_contour_px = 1.25;
  frame.fit.num_cameras = 2;
  frame.fit.seconds = 0.33;
  testing::TempDir dir;
  const std::string path = dir / "poses.json";
  WritePosesJson(path, body, BodyShape(), {"a", "b", "c"}, {frame}, 30.0);
  const PosesFile file = ReadPosesJson(path, body, {"a", "b", "c"});
  ASSERT_EQ(file.frames.size(), 1u);
  const TrackedFrame& read = file.frames[0];
  EXPECT_EQ(file.fps, 30.0);
  EXPECT_EQ(read.frame, 7);
  EXPECT_EQ(read.camera_iou, frame.camera_iou);
  EXPECT_EQ(read.mean_iou, frame.mean_iou);
  EXPECT_EQ(read.flags, frame.flags);
  EXPECT_EQ(read.seconds, frame.seconds);
  EXPECT_EQ(read.cpu_seconds, frame.cpu_seconds);
  EXPECT_EQ(read.fit.iterations, frame.fit.iterations);
  EXPECT_EQ(read.fit.mean_outside_px, frame.fit.mean_outside_px);
  EXPECT_EQ(read.fit.mean_contour_px, frame.fit.mean_contour_px);
  EXPECT_EQ(read.fit.num_cameras, frame.fit.num_cameras);
  EXPECT_EQ(read.fit.seconds, frame.fit.seconds);
}

}  // namespace
}  // namespace confluent
