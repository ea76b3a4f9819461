// End-to-end tests of `confluent calib convert`.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <Eigen/Geometry>

#include "calib/easymocap_io.h"
#include "tests/support/expect_same_rig.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using testing::RunConfluent;
using testing::TempDir;
using testing::WriteFile;

std::string Num(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

// A COLMAP model of two cameras 4 m from the origin looking at it; translations scaled by
// `units_per_metre`. Returns the expected cam_from_world rotations.
std::vector<Eigen::Matrix3d> WriteColmapFolder(const std::string& dir, double units_per_metre,
                                               const std::string& fx_text = "800") {
  std::vector<Eigen::Matrix3d> rotations;
  std::string images;
  for (int i = 0; i < 2; ++i) {
    // Camera i at angle a on a circle, looking at the origin; world z up.
    const double a = 1.3 * i;
    const Eigen::Vector3d center(4.0 * std::cos(a), 4.0 * std::sin(a), 1.0);
    const Eigen::Vector3d forward = -center.normalized();
    const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
    Eigen::Matrix3d rotation;
    rotation.row(0) = right.transpose();
    rotation.row(1) = forward.cross(right).transpose();
    rotation.row(2) = forward.transpose();
    rotations.push_back(rotation);
    const Eigen::Quaterniond q(rotation);
    const Eigen::Vector3d t = -rotation * center * units_per_metre;
    images += std::to_string(i + 1) + " " + Num(q.w()) + " " + Num(q.x()) + " " + Num(q.y()) + " " + Num(q.z()) +
              " " + Num(t.x()) + " " + Num(t.y()) + " " + Num(t.z()) + " 1 view" + std::to_string(i) + ".png\n\n";
  }
  WriteFile(dir + "/cameras.txt", "# CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]\n1 OPENCV 320 240 " + fx_text +
                                      " 801 160 120 -0.1 0.02 0.001 0.0005\n");
  WriteFile(dir + "/images.txt", images);
  return rotations;
}

TEST(CalibConvertTest, ConvertsColmapAndReadsBack) {
  TempDir dir;
  const std::vector<Eigen::Matrix3d> rotations = WriteColmapFolder(dir / "colmap", 1000.0);
  const auto result =
      RunConfluent({"calib", "convert", "--from", "colmap", "--input", dir / "colmap", "--out", dir / "out", "--units", "mm"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  EXPECT_NE(result.stdout_text.find("view0"), std::string::npos) << result.stdout_text;
  EXPECT_NE(result.stdout_text.find("320x240"), std::string::npos) << result.stdout_text;
  const Rig rig = ReadEasyMocap(dir / "out/intri.yml", dir / "out/extri.yml");
  ASSERT_EQ(rig.names(), (std::vector<std::string>{"view0", "view1"}));
  for (int i = 0; i < 2; ++i) {
    const Camera& camera = rig.cameras[i];
    EXPECT_EQ(camera.width, 320);
    EXPECT_EQ(camera.height, 240);
    EXPECT_DOUBLE_EQ(camera.K(0, 0), 800.0);
    EXPECT_DOUBLE_EQ(camera.K(1, 1), 801.0);
    EXPECT_DOUBLE_EQ(camera.K(0, 2), 159.5);  // COLMAP's pixel centres are at +0.5
    EXPECT_DOUBLE_EQ(camera.dist[0], -0.1);
    EXPECT_DOUBLE_EQ(camera.dist[3], 0.0005);
    EXPECT_LT((camera.rotation - rotations[i]).norm(), 1e-12);
    EXPECT_NEAR(camera.center_in_world().norm(), std::sqrt(17.0), 1e-9);  // metres
    // The camera sees the origin at its principal point.
    EXPECT_LT((camera.Project(Eigen::Vector3d::Zero()) - camera.K.col(2).head<2>()).norm(), 1e-9);
  }
}

TEST(CalibConvertTest, UpAxisOptionRotatesTheWorld) {
  TempDir dir;
  WriteColmapFolder(dir / "colmap", 1.0);
  const auto result = RunConfluent(
      {"calib", "convert", "--from", "colmap", "--input", dir / "colmap", "--out", dir / "out", "--up", "-x"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  const Rig rig = ReadEasyMocap(dir / "out/intri.yml", dir / "out/extri.yml");
  // view0 was at (4, 0, 1) in the file; with -x up it is 4 m below the ground.
  EXPECT_NEAR(rig.cameras[0].center_in_world().z(), -4.0, 1e-9);
}

TEST(CalibConvertTest, NanInKIsAnErrorNamingTheFile) {
  TempDir dir;
  WriteColmapFolder(dir / "colmap", 1.0, "nan");
  const auto result =
      RunConfluent({"calib", "convert", "--from", "colmap", "--input", dir / "colmap", "--out", dir / "out"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find(dir / "colmap/cameras.txt"), std::string::npos) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("nan"), std::string::npos) << result.stderr_text;
  EXPECT_EQ(result.stderr_text.find('\n'), result.stderr_text.size() - 1) << "not one line: " << result.stderr_text;
  EXPECT_FALSE(std::filesystem::exists(dir / "out/intri.yml"));

  // The same for the native format: NaN in K_<cam> of intri.yml.
  WriteFile(dir / "native/intri.yml",
            "%YAML:1.0\n---\nnames:\n  - \"a\"\nK_a: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
            "   data: [ .nan, 0., 160., 0., 800., 120., 0., 0., 1. ]\nH_a: 240\nW_a: 320\n");
  WriteFile(dir / "native/extri.yml",
            "%YAML:1.0\n---\nnames:\n  - \"a\"\nR_a: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n"
            "   data: [ 0., 0., 0. ]\nT_a: !!opencv-matrix\n   rows: 3\n   cols: 1\n   dt: d\n   data: [ 0., 0., 1. ]\n");
  const auto native =
      RunConfluent({"calib", "convert", "--from", "easymocap", "--input", dir / "native", "--out", dir / "out2"});
  EXPECT_EQ(native.exit_code, 1);
  EXPECT_NE(native.stderr_text.find(dir / "native/intri.yml"), std::string::npos) << native.stderr_text;
  EXPECT_NE(native.stderr_text.find("K_a"), std::string::npos) << native.stderr_text;
}

TEST(CalibConvertTest, NativeRigThroughPose2SimTomlAndBackKeepsEveryCameraTo1e9) {
  TempDir dir;
  WriteColmapFolder(dir / "colmap", 1.0);
  ASSERT_EQ(RunConfluent({"calib", "convert", "--from", "colmap", "--input", dir / "colmap", "--out", dir / "ours"}).exit_code, 0);
  // ours -> Pose2Sim TOML (a folder: OUT/Calib.toml) -> ours.
  const auto to_toml = RunConfluent(
      {"calib", "convert", "--from", "easymocap", "--input", dir / "ours", "--to", "pose2sim", "--out", dir / "p2s"});
  ASSERT_EQ(to_toml.exit_code, 0) << to_toml.stderr_text;
  EXPECT_NE(to_toml.stdout_text.find(dir / "p2s/Calib.toml"), std::string::npos) << to_toml.stdout_text;
  const auto back = RunConfluent(
      {"calib", "convert", "--from", "pose2sim", "--input", dir / "p2s/Calib.toml", "--out", dir / "back"});
  ASSERT_EQ(back.exit_code, 0) << back.stderr_text;

  const Rig ours = ReadEasyMocap(dir / "ours/intri.yml", dir / "ours/extri.yml");
  const Rig again = ReadEasyMocap(dir / "back/intri.yml", dir / "back/extri.yml");
  testing::ExpectSameRig(ours, again, 1e-9);

  const auto bad_target = RunConfluent(
      {"calib", "convert", "--from", "easymocap", "--input", dir / "ours", "--to", "vicon", "--out", dir / "x"});
  EXPECT_EQ(bad_target.exit_code, 2);
  EXPECT_NE(bad_target.stderr_text.find("--to"), std::string::npos) << bad_target.stderr_text;
}

TEST(CalibConvertTest, UnknownFormatOrUnitsAreUsageErrors) {
  TempDir dir;
  WriteColmapFolder(dir / "colmap", 1.0);
  auto result = RunConfluent({"calib", "convert", "--from", "vicon", "--input", dir / "colmap", "--out", dir / "out"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.stderr_text.find("unknown calibration format 'vicon'"), std::string::npos) << result.stderr_text;
  result = RunConfluent(
      {"calib", "convert", "--from", "colmap", "--input", dir / "colmap", "--out", dir / "out", "--units", "furlong"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.stderr_text.find("--units"), std::string::npos) << result.stderr_text;
  result = RunConfluent({"calib", "convert", "--from", "colmap", "--input", dir / "colmap"});
  EXPECT_EQ(result.exit_code, 2);  // --out is required
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

}  // namespace
}  // namespace confluent
