// Tests of Pose2Sim TOML calibrations (calib/pose2sim_io.h): a rig written and read back is the
// same rig to 1e-9, bad files are refused naming the problem, and Pose2Sim's own files (when
// ../shared/data is present) import, pass the rig check and agree with our Qualisys import.

#include "calib/pose2sim_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include <Eigen/Geometry>

#include "calib/importers.h"
#include "calib/rig_check.h"
#include "core/error.h"
#include "tests/support/expect_same_rig.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

namespace fs = std::filesystem;
using testing::SharedDataPath;
using testing::TempDir;

// Cameras with random orientations, among them the identity and a half turn (where the
// Rodrigues vector is least well conditioned), with and without k3, and names whose text
// order is not the rig's order.
Rig RandomRig() {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Rig rig;
  const char* names[] = {"cam10", "cam2", "left camera", "cam_01", "z"};
  for (int i = 0; i < 5; ++i) {
    Camera camera;
    camera.name = names[i];
    camera.width = 1088 + 64 * i;
    camera.height = 1920 - 32 * i;
    camera.K << 1600.0 + 37.3 * i, 0.25 * i, 540.0 + 3.7 * unit(random), 0.0, 1601.5 + 11.1 * i,
        960.0 + 4.1 * unit(random), 0.0, 0.0, 1.0;
    camera.dist << 0.1 * unit(random), 0.05 * unit(random), 1e-3 * unit(random), 1e-3 * unit(random),
        i % 2 ? 0.01 * unit(random) : 0.0;
    const Eigen::Vector3d axis = Eigen::Vector3d(unit(random), unit(random), unit(random)).normalized();
    const double angle = i == 0 ? 0.0 : i == 1 ? M_PI : M_PI * unit(random);
    camera.rotation = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    camera.translation = Eigen::Vector3d(unit(random), unit(random), 3.0 + unit(random));
    rig.cameras.push_back(camera);
  }
  return rig;
}

TEST(Pose2SimToml, WrittenAndReadBackKeepsEveryCameraTo1e9) {
  const Rig rig = RandomRig();
  const TempDir dir;
  const std::string path = dir / "Calib.toml";
  WritePose2SimToml(rig, path);
  const Rig back = ReadPose2SimToml(path);

  Rig expected = rig;
  expected.cameras[2].name = "left_camera";  // names become usable YAML keys
  testing::ExpectSameRig(expected, back, 1e-9);
  // Read through the format dispatch too: the rig passes the native checks.
  const Rig imported = ImportCalibration(ParseCalibFormat("pose2sim"), path);
  EXPECT_EQ(imported.size(), rig.size());
}

// Writes `text` to a .toml file and expects ReadPose2SimToml to refuse it, naming the file and
// `expected` in the message.
void ExpectRefused(const std::string& text, const std::string& expected) {
  const TempDir dir;
  const std::string path = dir / "Calib_bad.toml";
  std::ofstream(path) << text;
  try {
    ReadPose2SimToml(path);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find(expected), std::string::npos) << error.what();
  }
}

TEST(Pose2SimToml, BadFilesAreRefusedNamingTheProblem) {
  const std::string camera =
      "[cam_01]\nname = \"cam_01\"\nsize = [ 1088.0, 1920.0]\n"
      "matrix = [ [ 1681.2, 0.0, 532.9], [ 0.0, 1681.0, 948.1], [ 0.0, 0.0, 1.0]]\n"
      "distortions = [ -0.0007, 0.0021, 9.5e-06, 1.0e-05]\n"
      "rotation = [ 1.688, 1.048, -0.419]\ntranslation = [ 0.321, 0.956, 2.890]\n";
  // The good camera is read; each change of it below is refused.
  {
    const TempDir dir;
    const std::string path = dir / "Calib.toml";
    std::ofstream(path) << camera << "fisheye = false\n\n[metadata]\nadjusted = false\nerror = 0.0\n";
    EXPECT_EQ(ReadPose2SimToml(path).names(), std::vector<std::string>({"cam_01"}));
  }
  ExpectRefused(camera + "fisheye = true\n", "fisheye");
  ExpectRefused("[metadata]\nadjusted = false\n", "no camera");
  ExpectRefused(camera + "size = [1, 2]\n", "line 8");  // a key given twice: a TOML error with its line
  ExpectRefused("[cam_01]\nmatrix = [ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]\n", "'size'");
  std::string short_matrix = camera;
  short_matrix.replace(short_matrix.find("[ 0.0, 0.0, 1.0]"), 16, "[ 0.0, 0.0]");
  ExpectRefused(short_matrix, "'matrix'");
  std::string short_distortions = camera;
  short_distortions.replace(short_distortions.find("-0.0007, "), 9, "");
  ExpectRefused(short_distortions, "'distortions': expected 4 to 5 numbers, got 3");
  std::string text_rotation = camera;
  text_rotation.replace(text_rotation.find("1.688"), 5, "\"a\"");
  ExpectRefused(text_rotation, "'rotation': expected a number");
}

// Largest difference between two cameras' parameters: K and distortion (absolute), rotation
// (degrees) and centre (metres).
struct CameraDifference {
  double intrinsics = 0, distortion = 0, rotation_deg = 0, centre_m = 0;
};

CameraDifference Difference(const Camera& a, const Camera& b) {
  CameraDifference d;
  d.intrinsics = (a.K - b.K).cwiseAbs().maxCoeff();
  d.distortion = (a.dist - b.dist).cwiseAbs().maxCoeff();
  d.rotation_deg = Eigen::AngleAxisd(a.rotation.transpose() * b.rotation).angle() * 180.0 / M_PI;
  d.centre_m = (a.center_in_world() - b.center_in_world()).norm();
  return d;
}

TEST(Pose2SimToml, Pose2SimsOwnFilesImportPassTheRigCheckAndAgreeWithOurQualisysImport) {
  const fs::path data = SharedDataPath("real/pose2sim_single/calibration");
  if (data.empty()) GTEST_SKIP() << "../shared/data/real/pose2sim_single is absent";
  for (const char* file : {"Calib_qualisys.toml", "Calib_scene.toml"}) {
    SCOPED_TRACE(file);
    const Rig rig = ImportCalibration(CalibFormat::kPose2Sim, (data / file).string());
    ASSERT_EQ(rig.size(), 4);
    EXPECT_EQ(rig.cameras[0].width, 1088);
    EXPECT_EQ(rig.cameras[0].height, 1920);
    const RigCheckReport report = CheckRig(rig);
    EXPECT_TRUE(report.warnings.empty()) << report.ToString();
    for (const CameraCheck& camera : report.cameras) EXPECT_TRUE(camera.looks_at_volume) << camera.name;
  }

  // Pose2Sim's conversion of the Qualisys file against ours, camera by camera (cam_01 <-> cam01).
  const Rig pose2sim = ImportCalibration(CalibFormat::kPose2Sim, (data / "Calib_qualisys.toml").string());
  const Rig ours = ImportCalibration(CalibFormat::kQualisys, (data / "Calib.qca.txt").string());
  ASSERT_EQ(ours.size(), pose2sim.size());
  for (int i = 0; i < ours.size(); ++i) {
    const Camera& theirs = pose2sim.cameras[i];
    const Camera& mine = ours.cameras[i];
    SCOPED_TRACE(mine.name + " vs " + theirs.name);
    EXPECT_EQ(mine.width, theirs.width);
    EXPECT_EQ(mine.height, theirs.height);
    const CameraDifference d = Difference(mine, theirs);
    std::printf("%s: K %.2e px, distortion %.2e, rotation %.2e deg, centre %.2e m\n", mine.name.c_str(), d.intrinsics,
                d.distortion, d.rotation_deg, d.centre_m);
    EXPECT_LE(d.intrinsics, 1e-6);
    EXPECT_LE(d.distortion, 1e-9);
    EXPECT_LE(d.rotation_deg, 1e-5);
    EXPECT_LE(d.centre_m, 1e-6);
  }
}

}  // namespace
}  // namespace confluent
