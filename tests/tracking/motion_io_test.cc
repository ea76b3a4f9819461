// poses.json round trip of what `confluent track` reports per frame from it: the fit summary,
// the wall-clock and CPU seconds, the flags, the per-camera overlap and the lost-limb search's state.
#include "tracking/motion_io.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
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
  frame.limb_search = LimbSearch::kSkipped;
  frame.fruitless_search = {0.93, 0.47};
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
  EXPECT_EQ(read.limb_search, LimbSearch::kSkipped);
  EXPECT_EQ(read.fruitless_search.mean_iou, 0.93);
  EXPECT_EQ(read.fruitless_search.mean_contour_px, 0.47);
}

// A frame where the search did not run and none is pending writes neither, and reads back so;
// an unknown value is refused, naming the file.
TEST(PosesJson, LimbSearchStateDefaultsAndBadValues) {
  const BodyTemplate body;
  TrackedFrame frame;
  testing::TempDir dir;
  const std::string path = dir / "poses.json";
  WritePosesJson(path, body, BodyShape(), {}, {frame}, 25.0);
  const nlohmann::json written = nlohmann::json::parse(ReadTextFile(path));
  EXPECT_FALSE(written["frames"][0].contains("limb_search"));
  EXPECT_FALSE(written["frames"][0].contains("fruitless_limb_search"));
  const TrackedFrame read = ReadPosesJson(path, body, {}).frames.at(0);
  EXPECT_EQ(read.limb_search, LimbSearch::kNotTriggered);
  EXPECT_FALSE(read.fruitless_search.pending());

  nlohmann::json bad = written;
  bad["frames"][0]["limb_search"] = "sometimes";
  WriteTextFile(path, bad.dump());
  try {
    ReadPosesJson(path, body, {});
    FAIL() << "an unknown limb_search value was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("sometimes"), std::string::npos) << e.what();
  }
}

// A poses.json of the 37-DOF template (a run tracked before the neck and the wrists got their
// second axis): one angle per wrist, no neck. It reads as the pose it was (flexion, no deviation,
// neck upright); a joint given the wrong number of angles otherwise is refused, naming the file.
TEST(PosesJson, FilesOfTheOneAxisWristReadAsTheyWereWritten) {
  const BodyTemplate body;
  TrackedFrame frame;
  frame.pose.dofs[kJointLeftWrist] = {0.3, 0.0, 0.0};
  frame.pose.dofs[kJointRightElbow] = {0.5, 0.0, 0.0};
  testing::TempDir dir;
  const std::string path = dir / "poses.json";
  WritePosesJson(path, body, BodyShape(), {"a"}, {frame}, 25.0);
  nlohmann::json root = nlohmann::json::parse(ReadTextFile(path));
  nlohmann::json& angles = root["frames"][0]["joint_angles"];
  angles["left_wrist"] = {0.3};
  angles["right_wrist"] = {-0.2};
  angles.erase("neck");
  WriteTextFile(path, root.dump());
  const PosesFile file = ReadPosesJson(path, body, {"a"});
  ASSERT_EQ(file.frames.size(), 1u);
  const TemplatePose& read = file.frames[0].pose;
  EXPECT_EQ(read.dofs[kJointLeftWrist][0], 0.3);
  EXPECT_EQ(read.dofs[kJointLeftWrist][1], 0.0);
  EXPECT_EQ(read.dofs[kJointRightWrist][0], -0.2);
  EXPECT_EQ(read.dofs[kJointNeck][0], 0.0);
  EXPECT_EQ(read.dofs[kJointRightElbow][0], 0.5);
  angles["right_elbow"] = {0.5, 0.1};
  WriteTextFile(path, root.dump());
  try {
    ReadPosesJson(path, body, {"a"});
    FAIL() << "an elbow with two angles was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("right_elbow"), std::string::npos) << e.what();
  }
}

// The shape with its cross-sections and skirt comes back as written.
TEST(PosesJson, ShapeWithCrossSectionsRoundTrips) {
  const BodyTemplate body;
  BodyShape shape = BodyShape::Uniform(1.62);
  shape.girth_scale[int(BodySegment::kHead)] = 1.04;
  shape.depth_scale[int(BodySegment::kUpperTorso)] = 1.21;
  shape.taper_scale[int(BodySegment::kLowerTorso)] = 0.87;
  shape.depth_offset[int(BodySegment::kUpperTorso)] = 0.15;
  shape.depth_offset[int(BodySegment::kLowerTorso)] = -0.05;
  shape.mid_bulge[int(BodySegment::kLeftShank)] = 0.12;
  shape.skirt_length_m = 0.3;
  shape.skirt_flare_m = 0.08;
  testing::TempDir dir;
  const std::string path = dir / "poses.json";
  WritePosesJson(path, body, shape, {"a"}, {}, 25.0);
  const BodyShape read = ReadPosesJson(path, body, {"a"}).shape;
  EXPECT_EQ(read.length_scale, shape.length_scale);
  EXPECT_EQ(read.girth_scale, shape.girth_scale);
  EXPECT_EQ(read.depth_scale, shape.depth_scale);
  EXPECT_EQ(read.taper_scale, shape.taper_scale);
  EXPECT_EQ(read.depth_offset, shape.depth_offset);
  EXPECT_EQ(read.mid_bulge, shape.mid_bulge);
  EXPECT_EQ(read.skirt_length_m, shape.skirt_length_m);
  EXPECT_EQ(read.skirt_flare_m, shape.skirt_flare_m);
}

// A poses.json written before the cross-sections existed reads with the generic ones; a bad
// value is an error that names the file and the segment.
TEST(PosesJson, ShapeWithoutCrossSectionsReadsAsGenericAndBadOnesAreRefused) {
  const BodyTemplate body;
  testing::TempDir dir;
  const std::string path = dir / "poses.json";
  WritePosesJson(path, body, BodyShape::Uniform(1.8), {"a"}, {}, 25.0);
  nlohmann::json root = nlohmann::json::parse(ReadTextFile(path));
  for (const char* key : {"depth_scale", "taper_scale", "depth_offset", "mid_bulge"}) root["shape"].erase(key);
  WriteTextFile(path, root.dump());
  const BodyShape old = ReadPosesJson(path, body, {"a"}).shape;
  EXPECT_EQ(old.girth_scale, BodyShape::Uniform(1.8).girth_scale);
  for (int s = 0; s < kNumBodySegments; ++s) {
    EXPECT_EQ(old.depth_scale[s], 1.0);
    EXPECT_EQ(old.taper_scale[s], 1.0);
    EXPECT_EQ(old.depth_offset[s], 0.0);
    EXPECT_EQ(old.mid_bulge[s], 0.0);
  }
  WritePosesJson(path, body, BodyShape(), {"a"}, {}, 25.0);
  root = nlohmann::json::parse(ReadTextFile(path));
  root["shape"]["depth_scale"]["left_thigh"] = -0.5;
  WriteTextFile(path, root.dump());
  try {
    ReadPosesJson(path, body, {"a"});
    FAIL() << "a negative depth scale was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("depth_scale of segment left_thigh"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace confluent
