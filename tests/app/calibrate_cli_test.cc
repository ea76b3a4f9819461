// End to end: `confluent calibrate` on checkerboard images rendered into 3 known cameras.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "calib/easymocap_io.h"
#include "calib/synthetic_board.h"
#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

TEST(CalibrateCli, CalibratesThreeGeneratedCameras) {
  testing::TempDir dir;
  // Three neighbours of a 6-camera ring (60 degrees apart), low resolution.
  Rig ring = MakeRingRig(6, 3.0, 1.5, Eigen::Vector3d(0, 0, 1.0), 320, 240, 280.0,
                         (Vector5d() << -0.05, 0.01, 0.0, 0.0, 0.0).finished());
  Rig truth;
  truth.cameras.assign(ring.cameras.begin(), ring.cameras.begin() + 3);
  const CheckerboardSpec board{7, 5, 0.15};
  const auto poses = MakeBoardPoses(80, board, 0.8, 0.6, 1.5, 30.0, 40.0, 5);
  std::vector<CheckerboardRenderer> renderers;
  for (const Camera& camera : truth.cameras) renderers.emplace_back(camera, board);
  int frame = 0;
  for (std::size_t p = 0; p < poses.size() && frame < 36; ++p) {
    bool seen = false;
    for (const Camera& camera : truth.cameras) seen = seen || CheckerboardVisible(camera, board, poses[p], 6.0, 65.0);
    if (!seen) continue;
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", frame++);
    for (int c = 0; c < truth.size(); ++c) {
      const fs::path folder = fs::path(dir.path()) / "boards" / truth.cameras[c].name;
      fs::create_directories(folder);
      WriteImage((folder / name).string(), renderers[c].Render(poses[p], static_cast<std::uint32_t>(p * 7 + c)));
    }
  }
  const std::string out = dir / "calibration";
  const auto result = testing::RunConfluent({"calibrate", "--board", "7x5", "--square-mm", "150", "--images",
                                             dir / "boards", "--out", out, "--reference-camera", "cam01"});
  ASSERT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
  for (const Camera& camera : truth.cameras) EXPECT_NE(result.stdout_text.find(camera.name), std::string::npos);
  EXPECT_NE(result.stdout_text.find("joint RMS"), std::string::npos) << result.stdout_text;
  EXPECT_TRUE(fs::exists(fs::path(out) / "calibration_report.json"));

  const Rig got = ReadEasyMocap(out + "/intri.yml", out + "/extri.yml");
  ASSERT_EQ(got.size(), 3);
  // World = cam01's frame: express the truth there.
  const Eigen::Isometry3d ref_from_world = truth.cameras[1].cam_from_world();
  for (int c = 0; c < 3; ++c) {
    const Camera& t = truth.Get(got.cameras[c].name);
    EXPECT_NEAR(got.cameras[c].K(0, 0) / t.K(0, 0), 1.0, 0.01) << t.name;
    EXPECT_NEAR(got.cameras[c].K(1, 1) / t.K(1, 1), 1.0, 0.01) << t.name;
    EXPECT_LT((got.cameras[c].center_in_world() - ref_from_world * t.center_in_world()).norm(), 0.05) << t.name;
  }
  EXPECT_LT(got.Get("cam01").center_in_world().norm(), 1e-9);
}

TEST(CalibrateCli, MissingFolderFailsNamingIt) {
  testing::TempDir dir;
  const std::string missing = dir / "no_such_boards";
  const auto result = testing::RunConfluent(
      {"calibrate", "--board", "8x6", "--square-mm", "100", "--images", missing, "--out", dir / "out"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.stderr_text.find(missing), std::string::npos) << result.stderr_text;
  EXPECT_FALSE(fs::exists(dir / "out/intri.yml"));

  const auto bad_board = testing::RunConfluent(
      {"calibrate", "--board", "8by6", "--square-mm", "100", "--images", dir.path(), "--out", dir / "out"});
  EXPECT_NE(bad_board.exit_code, 0);
  EXPECT_NE(bad_board.stderr_text.find("--board"), std::string::npos) << bad_board.stderr_text;
}

}  // namespace
}  // namespace confluent
