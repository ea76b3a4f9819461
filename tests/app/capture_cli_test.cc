// End-to-end: `confluent capture info` and `confluent calib check` on generated captures,
// including every bad-input case of the foundation issue.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>

#include "calib/capture.h"
#include "calib/rig_check.h"
#include "core/error.h"
#include "core/image_io.h"
#include "silhouette/multiview.h"
#include "tests/app/capture_fixture.h"
#include "tests/support/mask_edits.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;
using testing::CommandResult;
using testing::RunConfluent;
using testing::TempDir;

// A failing command prints exactly one error line ("confluent <cmd>: ...") on stderr that
// names `file`, and exits non-zero. (Progress lines may precede it on stderr.)
void ExpectOneLineErrorNaming(const CommandResult& result, const std::string& file, const std::string& problem) {
  EXPECT_NE(result.exit_code, 0);
  EXPECT_LT(result.exit_code, 128) << "crashed (signal)";
  const std::regex error_line("(^|\n)confluent [a-z ]+: ");
  EXPECT_EQ(std::distance(std::sregex_iterator(result.stderr_text.begin(), result.stderr_text.end(), error_line),
                          std::sregex_iterator()),
            1)
      << result.stderr_text;
  EXPECT_NE(result.stderr_text.find(file), std::string::npos) << result.stderr_text;
  EXPECT_TRUE(std::regex_search(result.stderr_text, std::regex(problem, std::regex::icase))) << result.stderr_text;
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Rewrites the first match of `pattern` in the text file `path` by `replacement` ($1 etc. allowed).
void EditFirstMatch(const std::string& path, const std::string& pattern, const std::string& replacement) {
  const std::string text = Slurp(path);
  ASSERT_TRUE(std::regex_search(text, std::regex(pattern))) << pattern << " not in " << path;
  std::ofstream(path) << std::regex_replace(text, std::regex(pattern), replacement, std::regex_constants::format_first_only);
}

TEST(CaptureCli, ValidCaptureIsSummarised) {
  TempDir dir;
  testing::WriteFixtureCapture(dir / "cap");
  const CommandResult result = RunConfluent({"capture", "info", dir / "cap", "--decode"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  EXPECT_NE(result.stdout_text.find("cameras   4"), std::string::npos) << result.stdout_text;
  EXPECT_NE(result.stdout_text.find("frames    3"), std::string::npos);
  const Capture capture = Capture::Open(dir / "cap");
  EXPECT_TRUE(capture.has_masks());
  EXPECT_EQ(capture.ReadFrame(2, 1).width, 96);
  EXPECT_EQ(capture.ReadMask(1, 0).channels, 1);
}

TEST(CaptureCli, NanInKIsNamed) {
  TempDir dir;
  testing::WriteFixtureCapture(dir / "cap");
  // Replace the focal length of the first K matrix by .nan.
  EditFirstMatch(dir / "cap/intri.yml", "(K_cam00:[^\\[]*\\[\\s*)([-0-9.e+]+)", "$1.nan");
  ExpectOneLineErrorNaming(RunConfluent({"capture", "info", dir / "cap"}), "intri.yml", "nan|finite");
}

TEST(CaptureCli, NonNumericYamlEntryIsNamed) {
  TempDir dir;
  testing::WriteFixtureCapture(dir / "cap");
  EditFirstMatch(dir / "cap/intri.yml", "(K_cam01:[^\\[]*\\[\\s*)([-0-9.e+]+)", "$1abc");
  ExpectOneLineErrorNaming(RunConfluent({"capture", "info", dir / "cap"}), "intri.yml", "cam01|numeric|number|parse");
}

TEST(CaptureCli, UnknownDistortionModelIsNamed) {
  TempDir dir;
  testing::WriteFixtureCapture(dir / "cap");
  // An 8-coefficient rational model with non-zero k4..k6 cannot be represented.
  EditFirstMatch(dir / "cap/intri.yml", "dist_cam02:[^\\]]*\\]",
                 "dist_cam02: !!opencv-matrix\n   rows: 1\n   cols: 8\n   dt: d\n   data: [ 0.1, 0.01, 0., 0., 0., 0.2, 0.1, 0.05 ]");
  ExpectOneLineErrorNaming(RunConfluent({"capture", "info", dir / "cap"}), "intri.yml", "distortion");
}

TEST(CaptureCli, CameraWithoutImageFolderIsNamed) {
  TempDir dir;
  testing::WriteFixtureCapture(dir / "cap");
  fs::remove_all(dir / "cap/images/cam03");
  ExpectOneLineErrorNaming(RunConfluent({"capture", "info", dir / "cap"}), "cam03", "no image folder|missing");
}

TEST(CaptureCli, UnequalFrameCountsListEveryCamera) {
  TempDir dir;
  testing::WriteFixtureCapture(dir / "cap");
  fs::remove(dir / "cap/images/cam01/000002.png");
  const CommandResult result = RunConfluent({"capture", "info", dir / "cap"});
  ExpectOneLineErrorNaming(result, "images", "unequal frame counts");
  EXPECT_NE(result.stderr_text.find("cam00: 3"), std::string::npos) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("cam01: 2"), std::string::npos) << result.stderr_text;
}

TEST(CaptureCli, MissingFrameInTheMiddleIsNamed) {
  TempDir dir;
  testing::WriteFixtureCapture(dir / "cap");
  fs::rename(dir / "cap/images/cam02/000001.png", dir / "cap/images/cam02/000007.png");
  ExpectOneLineErrorNaming(RunConfluent({"capture", "info", dir / "cap"}), "cam02", "frame 1 is missing");
}

TEST(CaptureCli, TruncatedPngIsNamed) {
  TempDir dir;
  testing::WriteFixtureCapture(dir / "cap");
  const std::string victim = dir / "cap/images/cam01/000001.png";
  fs::resize_file(victim, fs::file_size(victim) * 2 / 3);
  ExpectOneLineErrorNaming(RunConfluent({"capture", "info", dir / "cap", "--decode"}), "cam01/000001.png",
                           "truncated|corrupt");
}

TEST(CaptureCli, ImageSizeDifferentFromCalibrationIsNamed) {
  TempDir dir;
  testing::WriteFixtureCapture(dir / "cap");
  WriteImage(dir / "cap/images/cam00/000001.png", Image(50, 40, 3));
  ExpectOneLineErrorNaming(RunConfluent({"capture", "info", dir / "cap"}), "cam00/000001.png", "50x40");
}

// A one-frame capture of 6 ring cameras at 160x120 with exact masks.
void WriteSixCameraCapture(const std::string& path) {
  testing::FixtureOptions options;
  options.num_cameras = 6;
  options.num_frames = 1;
  options.width = 160;
  options.height = 120;
  testing::WriteFixtureCapture(path, options);
}

TEST(CalibCheck, ConsistentRigAndMasksPass) {
  TempDir dir;
  WriteSixCameraCapture(dir / "cap");
  const CommandResult result = RunConfluent({"calib", "check", dir / "cap", "--out", dir / "check"});
  EXPECT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
  for (int c = 0; c < 6; ++c) EXPECT_TRUE(fs::exists(dir / ("check/cam0" + std::to_string(c) + ".png")));
  EXPECT_NE(result.stdout_text.find("mean IoU"), std::string::npos);
}

// calib check's multi-view confidence of `dir`/cap's masks: rig camera name -> {explained, covered, confidence}.
nlohmann::json CheckedMaskConfidence(const TempDir& dir) {
  const CommandResult result = RunConfluent({"calib", "check", dir / "cap", "--out", dir / "check"});
  EXPECT_NE(result.stdout_text.find("multi-view confidence"), std::string::npos) << result.stdout_text;
  const nlohmann::json json = nlohmann::json::parse(Slurp(dir / "check/check.json"));
  EXPECT_TRUE(json.contains("mask_confidence")) << json.dump(2);
  return json.value("mask_confidence", nlohmann::json::object());
}

TEST(CalibCheck, ReportsEachMasksMultiViewConfidenceAndFlagsAShiftedOne) {
  TempDir dir;
  WriteSixCameraCapture(dir / "cap");
  // Exact masks: every camera above silhouettes' flagging threshold, its mask explained by the others' hull.
  const double flagged_below = MultiViewOptions().min_confidence;
  const nlohmann::json exact = CheckedMaskConfidence(dir);
  ASSERT_EQ(exact.size(), 6u) << exact.dump();
  for (const auto& [name, view] : exact.items()) {
    EXPECT_GE(view["confidence"].get<double>(), flagged_below) << name << " " << view.dump();
    EXPECT_GT(view["explained"].get<double>(), 0.95) << name << " " << view.dump();
  }
  // cam02's mask moved 30 px sideways (a fifth of the image): it no longer agrees with the others.
  const Image mask = Capture::Open(dir / "cap").ReadMask(2, 0);
  WriteImage(dir / "cap/masks/cam02/000000.png", testing::ShiftedMask(mask, 30));
  const nlohmann::json moved = CheckedMaskConfidence(dir);
  ASSERT_EQ(moved.size(), 6u) << moved.dump();
  EXPECT_LT(moved["cam02"]["confidence"].get<double>(), flagged_below) << moved.dump();
  EXPECT_LT(moved["cam02"]["explained"].get<double>(), 0.9) << moved.dump();
  for (const auto& [name, view] : moved.items()) {
    if (name == "cam02") continue;
    EXPECT_GT(view["explained"].get<double>(), 0.95) << name << " " << view.dump();
  }
}

TEST(CalibCheck, HullOfExactMasksMatchesEachCamera) {
  TempDir dir;
  WriteSixCameraCapture(dir / "cap");
  const Capture capture = Capture::Open(dir / "cap");
  std::vector<Image> masks;
  for (int c = 0; c < capture.num_cameras(); ++c) masks.push_back(capture.ReadMask(c, 0));
  const std::vector<double> ious = VisualHullConsistency(capture.rig(), masks, {});
  ASSERT_EQ(ious.size(), 6u);
  // A sphere's hull from 5 ring views (one 120-degree gap) is larger than the sphere: ~0.84 at
  // 160x120, while a wrong calibration or mask falls below 0.3.
  for (double iou : ious) {
    EXPECT_GT(iou, 0.8);
    EXPECT_LE(iou, 1.0);
  }
  // Held-out form: hull from cameras 0-3 scored in 4 and 5.
  const std::vector<double> heldout = VisualHullConsistency(capture.rig(), masks, {4, 5});
  ASSERT_EQ(heldout.size(), 2u);
  EXPECT_GT(heldout[0], 0.8);
  // Carved on three threads: the same hulls, byte for byte.
  VisualHullOptions threaded;
  threaded.threads = 3;
  std::vector<Image> hulls, threaded_hulls;
  EXPECT_EQ(VisualHullConsistency(capture.rig(), masks, {}, {}, &hulls), ious);
  EXPECT_EQ(VisualHullConsistency(capture.rig(), masks, {}, threaded, &threaded_hulls), ious);
  ASSERT_EQ(threaded_hulls.size(), hulls.size());
  for (std::size_t c = 0; c < hulls.size(); ++c) EXPECT_EQ(threaded_hulls[c].data, hulls[c].data) << c;
  // An empty mask in one camera makes the hull empty for every other camera.
  masks[2] = Image(160, 120, 1);
  const std::vector<double> broken = VisualHullConsistency(capture.rig(), masks, {});
  EXPECT_LT(broken[0], 0.1);
}

TEST(CalibCheck, MillimetreRigAndCameraFacingAwayAreWarned) {
  testing::FixtureOptions options;
  Rig rig = testing::FixtureRig(options);
  RigCheckReport report = CheckRig(rig);
  EXPECT_TRUE(report.warnings.empty()) << report.ToString();
  EXPECT_NEAR(report.volume_center.z(), 1.0, 1e-6);
  EXPECT_NEAR(report.cameras[0].distance_to_center_m, std::hypot(3.0, 0.2), 1e-6);

  Rig millimetres = rig;
  TransformWorld(&millimetres, Eigen::Matrix3d::Identity(), 1000.0);
  report = CheckRig(millimetres);
  ASSERT_FALSE(report.warnings.empty());
  EXPECT_NE(report.warnings[0].find("units"), std::string::npos) << report.ToString();

  Rig turned = rig;
  const Eigen::Matrix3d half_turn = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  turned.cameras[1].rotation = half_turn * turned.cameras[1].rotation;
  turned.cameras[1].translation = half_turn * turned.cameras[1].translation;  // same centre, looking away
  report = CheckRig(turned);
  EXPECT_FALSE(report.cameras[1].looks_at_volume);
  EXPECT_TRUE(report.cameras[0].looks_at_volume);
}

}  // namespace
}  // namespace confluent
