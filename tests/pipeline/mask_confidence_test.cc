// RUN/mask_confidence.json: what the silhouette stage checked round-trips, and the low
// camera-frames read as ranges per camera, worst camera first.

#include "pipeline/mask_confidence.h"

#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

Rig ThreeCameras() {
  Rig rig;
  for (const char* name : {"cam00", "cam01", "cam02"}) {
    Camera camera;
    camera.name = name;
    rig.cameras.push_back(camera);
  }
  return rig;
}

TEST(MaskConfidence, RoundTripsAndListsTheLowCameraFramesAsRanges) {
  const Rig rig = ThreeCameras();
  std::vector<CameraFrameConfidence> checked;
  for (int frame : {0, 1, 2, 3, 7, 9}) {
    checked.push_back({0, frame, 0.95});
    checked.push_back({1, frame, frame == 3 ? 0.5 : 0.9});
    checked.push_back({2, frame, frame <= 2 || frame == 7 ? 0.3 : 0.85});  // frames 0-2 and 7 low
  }
  const MaskTrust trust = SummarizeMaskTrust(rig, checked, 0.8);
  testing::TempDir dir;
  const std::string path = dir / "mask_confidence.json";
  WriteMaskConfidence(path, MakeMaskConfidenceRecord(rig, trust, 0.8, "sample"));
  const MaskConfidenceRecord record = ReadMaskConfidence(path);
  EXPECT_EQ(record.source, "sample");
  EXPECT_EQ(record.camera_frames, 18);
  EXPECT_EQ(record.camera_names, (std::vector<std::string>{"cam00", "cam01", "cam02"}));
  EXPECT_NEAR(record.camera_confidence[2], (4 * 0.3 + 2 * 0.85) / 6, 1e-12);
  EXPECT_EQ(record.camera_checked, (std::vector<int>{6, 6, 6}));
  EXPECT_EQ(record.low_frames.size(), 5u);
  EXPECT_EQ(record.warning, trust.warning);
  EXPECT_FALSE(record.warning.empty());  // cam02's mean is below 0.8
  EXPECT_EQ(LowConfidenceList(record), "cam02 frames 0-2, 7; cam01 frame 3");
  EXPECT_EQ(LowConfidenceList(record, 1), "cam02 frames 0-2, 7; and 1 more camera(s)");

  std::ofstream(path) << "{\"source\": \"sample\"}";
  EXPECT_THROW(ReadMaskConfidence(path), InputError);
}

}  // namespace
}  // namespace confluent
