// End to end: `confluent synth --preset tiny`, then `confluent track` on its ground-truth masks
// with the held-out cameras excluded; joint error against the studio skeleton's joints. The
// performance is sampled at 12.5 fps so that 10 frames cover the arms rising over the head.

#include <gtest/gtest.h>

#include <algorithm>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/bvh_io.h"
#include "core/mesh_io.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

namespace fs = std::filesystem;

TEST(TrackCommand, TracksTheTinyStudioCapture) {
  const testing::TempDir dir;
  const std::string capture = dir / "cap";
  const testing::CommandResult synth = testing::RunConfluent({"synth", "--preset", "tiny", "--fps", "12.5", "--out", capture});
  ASSERT_EQ(synth.exit_code, 0) << synth.stderr_text;
  const std::string gt = capture + "_gt";
  const std::string run = dir / "run";
  const testing::CommandResult track =
      testing::RunConfluent({"track", capture, "--masks", gt + "/masks", "--exclude-camera", "holdout0", "--exclude-camera",
                             "holdout1", "--gt-joints", gt + "/joints.json", "--out", run});
  ASSERT_EQ(track.exit_code, 0) << track.stderr_text << track.stdout_text;
  EXPECT_NE(track.stdout_text.find("frame 000009"), std::string::npos) << track.stdout_text;
  const nlohmann::json summary = nlohmann::json::parse(ReadTextFile(run + "/track_summary.json"));
  EXPECT_EQ(summary.at("frames").get<int>(), 10);
  // Loose thresholds: 160x120 images, 4 cameras.
  EXPECT_LT(summary.at("joint_error_mean_m").get<double>(), 0.05) << track.stdout_text;
  EXPECT_GT(summary.at("heldout_iou_mean").get<double>(), 0.75) << track.stdout_text;
  const nlohmann::json poses = nlohmann::json::parse(ReadTextFile(run + "/poses.json"));
  ASSERT_EQ(poses.at("frames").size(), 10u);
  EXPECT_EQ(poses.at("frames")[3].at("joint_positions").size(), 22u);
  int searched = 0;  // the summary counts what the frames record
  for (const nlohmann::json& frame : poses.at("frames")) searched += frame.value("limb_search", std::string()) == "ran";
  EXPECT_EQ(summary.at("limb_search_frames").get<int>(), searched);
  EXPECT_TRUE(poses.at("shape").at("length_scale").contains("left_forearm"));
  // The shape was learned over the first frames: frame 0 and frame 5 (the capture has 10).
  const std::vector<std::string> first_flags = poses.at("frames")[0].at("flags");
  EXPECT_NE(std::find(first_flags.begin(), first_flags.end(), "shape:2"), first_flags.end());
  BvhReadOptions options;
  options.scale = 0.01;
  options.y_up_to_z_up = true;
  const BvhMotion motion = ReadBvh(run + "/motion.bvh", options);
  EXPECT_EQ(motion.frames.size(), 10u);
  const Mesh mesh = ReadMesh(run + "/template/000009.ply");
  EXPECT_TRUE(mesh.has_face_labels());
  EXPECT_TRUE(fs::exists(run + "/overlays/holdout0/000000.png"));
  // BlazePose looked at the first frame (the tracker's landmark evidence) ...
  EXPECT_NE(track.stdout_text.find("frame 0: landmarks "), std::string::npos) << track.stdout_text;
  // ... and without the segmenter the tracking goes on from the silhouettes, saying why.
  const testing::CommandResult alone = testing::RunConfluent(
      {"track", capture, "--masks", gt + "/masks", "--exclude-camera", "holdout0", "--exclude-camera", "holdout1",
       "--frames", "0:2", "--out", dir / "run_alone"},
      "CONFLUENT_PERSON_SEGMENTER=" + dir / "missing/segment.js");
  ASSERT_EQ(alone.exit_code, 0) << alone.stderr_text << alone.stdout_text;
  EXPECT_NE(alone.stdout_text.find("no landmarks (tracking from the silhouettes alone)"), std::string::npos)
      << alone.stdout_text;
  EXPECT_NE(alone.stdout_text.find("missing/segment.js"), std::string::npos) << alone.stdout_text;

  // Unknown camera names are usage errors.
  const testing::CommandResult bad = testing::RunConfluent({"track", capture, "--masks", gt + "/masks", "--exclude-camera", "nope", "--out", dir / "run2"});
  EXPECT_NE(bad.exit_code, 0);
  // So is a girth inflation out of range, named.
  const testing::CommandResult fat = testing::RunConfluent(
      {"track", capture, "--masks", gt + "/masks", "--girth-inflation", "0.7", "--out", dir / "run3"});
  EXPECT_NE(fat.exit_code, 0);
  EXPECT_NE(fat.stderr_text.find("--girth-inflation: must be within [0, 0.5]"), std::string::npos) << fat.stderr_text;
  const testing::CommandResult many = testing::RunConfluent(
      {"track", capture, "--masks", gt + "/masks", "--shape-samples", "51", "--out", dir / "run4"});
  EXPECT_NE(many.exit_code, 0);
  EXPECT_NE(many.stderr_text.find("--shape-samples: must be within [0, 50]"), std::string::npos) << many.stderr_text;
  const testing::CommandResult coarse = testing::RunConfluent(
      {"track", capture, "--masks", gt + "/masks", "--downscale", "17", "--out", dir / "run5"});
  EXPECT_NE(coarse.exit_code, 0);
  EXPECT_NE(coarse.stderr_text.find("--downscale: must be within [0, 16]"), std::string::npos) << coarse.stderr_text;
}

}  // namespace
}  // namespace confluent
