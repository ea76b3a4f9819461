// Real data (../shared/data, skipped when absent): the Tsinghua 20-camera dome imported from
// its plain-text calibration must pass `calib check`, and a visual hull from 18 cameras must
// match the real silhouettes of the 2 others. (The ground-truth masks of cam15 and cam17 also
// mark the tent ceiling as foreground, so those two are not used as held-out cameras.)

#include <gtest/gtest.h>

#include <filesystem>
#include <regex>

#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

TEST(RealCalibration, TsinghuaImportPassesCheckAndHullMatchesHeldOutMasks) {
  const std::string data = testing::SharedDataPath("real/tsinghua_lkB");
  if (data.empty()) GTEST_SKIP() << "../shared/data/real/tsinghua_lkB is absent";
  testing::TempDir dir;
  const std::string capture = dir / "lkB";
  auto convert = testing::RunConfluent({"calib", "convert", "--from", "plain", "--input", data + "/CalibParamsB.txt",
                                        "--units", "dm", "--up", "-y", "--out", capture});
  ASSERT_EQ(convert.exit_code, 0) << convert.stderr_text;
  // Image k+1 <-> silhouette k <-> camera k (see ../shared/data/README.md).
  for (int k = 0; k < 20; ++k) {
    char camera[16], image[64], mask[64];
    std::snprintf(camera, sizeof camera, "cam%02d", k);
    std::snprintf(image, sizeof image, "wd_data/lkB_000%02d.png", k + 1);
    std::snprintf(mask, sizeof mask, "lkB_segmented/lkB_000%d_segmented.png", k);
    fs::create_directories(fs::path(capture) / "images" / camera);
    fs::create_directories(fs::path(capture) / "masks" / camera);
    fs::create_symlink(fs::path(data) / image, fs::path(capture) / "images" / camera / "000000.png");
    fs::create_symlink(fs::path(data) / mask, fs::path(capture) / "masks" / camera / "000000.png");
  }
  auto check = testing::RunConfluent({"calib", "check", capture, "--heldout", "cam03", "--heldout", "cam12",
                                      "--min-iou", "0.85", "--hull-resolution", "200", "--out", dir / "check"});
  std::printf("%s\n", check.stdout_text.c_str());
  EXPECT_EQ(check.exit_code, 0) << check.stderr_text;
  std::smatch match;
  std::string text = check.stdout_text;
  int scored = 0;
  for (const std::regex iou("(cam03|cam12) +IoU ([0-9.]+)"); std::regex_search(text, match, iou);
       text = match.suffix()) {
    EXPECT_GT(std::stod(match[2]), 0.85) << match[1];
    ++scored;
  }
  EXPECT_EQ(scored, 2) << check.stdout_text;
}

}  // namespace
}  // namespace confluent
