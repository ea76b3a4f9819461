// End to end: `confluent synth --preset tiny` renders a capture with ground-truth masks, then
// `confluent silhouettes` must reproduce them; a missing plate falls back with a warning.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

TEST(SilhouettesCli, TinySynthCaptureMatchesGroundTruthAndMissingPlateFallsBack) {
  testing::TempDir dir;
  const std::string capture = dir / "tiny";
  auto synth = testing::RunConfluent({"synth", "--preset", "tiny", "--out", capture, "--gt", dir / "tiny_gt"});
  ASSERT_EQ(synth.exit_code, 0) << synth.stderr_text;
  auto run = testing::RunConfluent({"silhouettes", capture, "--out", dir / "masks", "--compare", dir / "tiny_gt/masks"});
  ASSERT_EQ(run.exit_code, 0) << run.stderr_text;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(run.stdout_text, match, std::regex("IoU against .*: mean ([0-9.]+), worst ([0-9.]+)")))
      << run.stdout_text;
  // 160x120 images: a one-pixel boundary error is already a few percent of IoU.
  EXPECT_GE(std::stod(match[1]), 0.95) << run.stdout_text;
  EXPECT_GE(std::stod(match[2]), 0.85) << run.stdout_text;
  EXPECT_TRUE(fs::exists(dir / "masks/cam00/000000.png"));
  EXPECT_TRUE(fs::exists(dir / "masks/overlays/000009.png"));
  EXPECT_TRUE(fs::exists(dir / "masks/summary.json"));
  EXPECT_EQ(run.stderr_text.find("warning"), std::string::npos) << run.stderr_text;

  // Without cam01's plate: learned background for cam01, with a warning; a frame range.
  fs::remove(capture + "/background/cam01.png");
  auto fallback = testing::RunConfluent(
      {"silhouettes", capture, "--out", dir / "masks2", "--frames", "2:5", "--method", "plate", "--no-overlays"});
  ASSERT_EQ(fallback.exit_code, 0) << fallback.stderr_text;
  EXPECT_NE(fallback.stderr_text.find("cam01: no clean plate"), std::string::npos) << fallback.stderr_text;
  EXPECT_TRUE(fs::exists(dir / "masks2/cam01/000004.png"));
  EXPECT_FALSE(fs::exists(dir / "masks2/cam01/000005.png"));
  EXPECT_FALSE(fs::exists(dir / "masks2/overlays"));

  // A plate of another size: a clear error naming the file.
  WriteImage(capture + "/background/cam00.png", Image(80, 60, 3));
  auto bad = testing::RunConfluent({"silhouettes", capture, "--frames", "0:1", "--out", dir / "masks3"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.stderr_text.find("background/cam00.png"), std::string::npos) << bad.stderr_text;
  EXPECT_NE(bad.stderr_text.find("80x60"), std::string::npos) << bad.stderr_text;
}

}  // namespace
}  // namespace confluent
