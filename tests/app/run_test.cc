// End-to-end tests of `confluent run` and `confluent evaluate` on the tiny studio capture:
// outputs against the studio's ground truth, resuming after a kill (file modification times),
// and bad input (clear message, non-zero exit, finished output kept).

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;
using testing::RunConfluent;

// One tiny capture (4 ring + 2 held-out cameras, 160x120, 10 frames at 12.5 fps) for the suite.
class RunCommandTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new testing::TempDir();
    const testing::CommandResult synth =
        RunConfluent({"synth", "--preset", "tiny", "--fps", "12.5", "--out", *dir_ / "capture"});
    ASSERT_EQ(synth.exit_code, 0) << synth.stderr_text;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string Capture() { return *dir_ / "capture"; }
  static std::string Truth() { return *dir_ / "capture_gt"; }
  static std::vector<std::string> RunArgs(const std::string& run) {
    return {"run", Capture(), "--out", run, "--exclude-camera", "holdout0", "--exclude-camera", "holdout1",
            "--render-width", "160", "--render-height", "120"};
  }
  static testing::TempDir* dir_;
};
testing::TempDir* RunCommandTest::dir_ = nullptr;

std::map<std::string, fs::file_time_type> ModificationTimes(const std::string& root) {
  std::map<std::string, fs::file_time_type> times;
  for (const auto& entry : fs::recursive_directory_iterator(root))
    if (entry.is_regular_file()) times[fs::relative(entry.path(), root).string()] = entry.last_write_time();
  return times;
}

int CountFiles(const std::string& dir, const std::string& extension) {
  if (!fs::is_directory(dir)) return 0;
  int n = 0;
  for (const auto& entry : fs::directory_iterator(dir)) n += entry.path().extension() == extension;
  return n;
}

// SIGKILLs every process whose command line mentions `marker` (no pkill needed).
void KillProcessesMentioning(const std::string& marker) {
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "cmdline", std::ios::binary);
    std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (cmdline.find(marker) != std::string::npos && cmdline.find("confluent") != std::string::npos)
      ::kill(std::stoi(name), SIGKILL);
  }
}

TEST_F(RunCommandTest, CaptureToThreeDVideoAndHeldOutEvaluation) {
  testing::TempDir out;
  const std::string run = out / "run";
  const testing::CommandResult result = RunConfluent(RunArgs(run));
  ASSERT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
  for (const char* file : {"run.json", "timings.csv", "poses.json", "motion.bvh", "correspondences.json",
                           "template_reference.ply"})
    EXPECT_TRUE(fs::exists(fs::path(run) / file)) << file;
  EXPECT_EQ(CountFiles(run + "/masks/holdout0", ".png"), 10);  // held-out cameras get masks too
  EXPECT_EQ(CountFiles(run + "/template", ".ply"), 10);
  EXPECT_EQ(CountFiles(run + "/scan", ".ply"), 10);
  EXPECT_EQ(CountFiles(run + "/renders/orbit", ".png"), 10);
  // Every frame went through the silhouette and then the photo-consistency refinement.
  EXPECT_NE((result.stdout_text + result.stderr_text).find("photo refinement: mean flow between neighbouring cameras"),
            std::string::npos)
      << result.stdout_text;
  std::ifstream timings(run + "/timings.csv");
  int photo_rows = 0;
  for (std::string line; std::getline(timings, line);) photo_rows += line.rfind("photo_refine,", 0) == 0;
  EXPECT_EQ(photo_rows, 10);
  const nlohmann::json record = nlohmann::json::parse(std::ifstream(run + "/run.json"));
  EXPECT_EQ(record["excluded_cameras"], (std::vector<std::string>{"holdout0", "holdout1"}));
  EXPECT_FALSE(record["input_checksums"]["scan"].get<std::string>().empty());

  const testing::CommandResult evaluate =
      RunConfluent({"evaluate", Capture(), "--run", run, "--heldout", "holdout0", "--heldout", "holdout1", "--masks",
                    Truth() + "/masks", "--gt-meshes", Truth() + "/meshes"});
  ASSERT_EQ(evaluate.exit_code, 0) << evaluate.stdout_text << evaluate.stderr_text;
  const nlohmann::json metrics = nlohmann::json::parse(std::ifstream(run + "/metrics.json"));
  // The tiny capture is 160x120 with 4 tracking cameras: loose bounds that still catch a broken
  // stage (a misplaced scan has IoU near 0 and an error of decimetres).
  EXPECT_GT(metrics["scan"]["iou_mean"].get<double>(), 0.6);
  EXPECT_GT(metrics["scan"]["psnr_db_mean"].get<double>(), 15.0);
  EXPECT_LT(metrics["scan_vertex_error_mean_m"].get<double>(), 0.08);
  EXPECT_EQ(metrics["rows"].size(), 20u);
  // The error split: pixels only one silhouette covers compare actor with background, so the
  // texture alone (inside both silhouettes) scores higher than the union, and the XOR band holds
  // part, not all, of the error.
  EXPECT_GT(metrics["scan"]["psnr_inside_db_mean"].get<double>(), metrics["scan"]["psnr_db_mean"].get<double>());
  const double share = metrics["scan"]["xor_error_share_percent_mean"].get<double>();
  EXPECT_GT(share, 0.0);
  EXPECT_LT(share, 100.0);
  for (const char* file : {"metrics.csv", "report.html", "plots/iou_per_frame.png", "plots/psnr_per_frame.png",
                           "plots/error_heatmap_holdout0.png", "evaluation/holdout1/000000.png"})
    EXPECT_TRUE(fs::exists(fs::path(run) / file)) << file;
  EXPECT_NE(evaluate.stdout_text.find("held-out evaluation"), std::string::npos);

  // The views are scored over the held-out cameras' clean plates (the synthetic capture has them),
  // with the input colours matched to each held-out camera's response and the outline matted.
  // Without the match the colours inside change; over black with a binary outline, only the
  // pixels outside the rendered silhouette:
  // the union's PSNR moves, the PSNR inside both silhouettes does not.
  EXPECT_EQ(metrics["background"], "clean plate");
  EXPECT_EQ(metrics["colour_matched"], true);
  auto evaluate_with = [&](const std::vector<std::string>& options) {
    std::vector<std::string> args = {"evaluate", Capture(), "--run", run, "--heldout", "holdout0", "--heldout", "holdout1",
                                     "--masks", Truth() + "/masks", "--side-by-side-every", "0"};
    args.insert(args.end(), options.begin(), options.end());
    const testing::CommandResult result = RunConfluent(args);
    EXPECT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
    return nlohmann::json::parse(std::ifstream(run + "/metrics.json"));
  };
  EXPECT_EQ(metrics["edge_softness_px"], 0.5);
  const nlohmann::json unmatched = evaluate_with({"--no-colour-match", "--edge-softness", "0"});
  EXPECT_EQ(unmatched["colour_matched"], false);
  EXPECT_GT(std::abs(unmatched["scan"]["psnr_inside_db_mean"].get<double>() - metrics["scan"]["psnr_inside_db_mean"].get<double>()), 1e-6);
  const nlohmann::json black = evaluate_with({"--background=black"});
  EXPECT_EQ(black["background"], "black");
  EXPECT_EQ(black["colour_matched"], false);
  EXPECT_NEAR(black["scan"]["psnr_inside_db_mean"].get<double>(), unmatched["scan"]["psnr_inside_db_mean"].get<double>(), 1e-9);
  EXPECT_GT(std::abs(black["scan"]["psnr_db_mean"].get<double>() - unmatched["scan"]["psnr_db_mean"].get<double>()), 0.01);
  EXPECT_EQ(black["scan"]["iou_mean"], metrics["scan"]["iou_mean"]);
  // The texturing options, as render's: one camera per pixel changes the colours, not the outline.
  EXPECT_EQ(metrics["texturing"], "best 3 cameras, feather 8 px, no colour balance");
  const nlohmann::json nearest = evaluate_with({"--best-k", "1"});
  EXPECT_EQ(nearest["texturing"], "best 1 camera, feather 8 px, no colour balance");
  EXPECT_GT(std::abs(nearest["scan"]["psnr_inside_db_mean"].get<double>() - metrics["scan"]["psnr_inside_db_mean"].get<double>()), 1e-6);
  EXPECT_EQ(nearest["scan"]["iou_mean"], metrics["scan"]["iou_mean"]);
}

TEST_F(RunCommandTest, KilledRunResumesWithoutRecomputingFinishedFrames) {
  testing::TempDir out;
  const std::string run = out / "run";
  std::atomic<bool> finished{false};
  testing::CommandResult first;
  std::thread runner([&] {
    first = RunConfluent(RunArgs(run));
    finished = true;
  });
  // Kill it once a few frames are tracked.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (!finished && !fs::exists(run + "/tracking/000003.json") && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  KillProcessesMentioning(run);
  runner.join();
  ASSERT_NE(first.exit_code, 0) << "the run finished before it could be killed";
  ASSERT_TRUE(fs::exists(run + "/tracking/000003.json"));
  ASSERT_LT(CountFiles(run + "/scan", ".ply"), 10);
  const auto before = ModificationTimes(run);

  const testing::CommandResult second = RunConfluent(RunArgs(run));
  ASSERT_EQ(second.exit_code, 0) << second.stdout_text << second.stderr_text;
  EXPECT_EQ(CountFiles(run + "/template", ".ply"), 10);
  EXPECT_EQ(CountFiles(run + "/scan", ".ply"), 10);
  const auto after = ModificationTimes(run);
  int kept = 0;
  for (const auto& [file, time] : before) {
    if (file == "timings.csv" || file.find(".tmp") != std::string::npos) continue;  // the log is rewritten by design
    if (file.rfind("masks/", 0) == 0 || file.rfind("tracking/", 0) == 0 || file.rfind("template/", 0) == 0) {
      ASSERT_TRUE(after.count(file)) << file;
      EXPECT_EQ(after.at(file), time) << file << " was recomputed";
      ++kept;
    }
  }
  EXPECT_GE(kept, 4 * 6 + 2 * 4);  // at least 4 frames of masks and of tracking state + template
  // A third invocation has nothing left to do.
  const auto finished_times = ModificationTimes(run);
  const testing::CommandResult third = RunConfluent(RunArgs(run));
  ASSERT_EQ(third.exit_code, 0) << third.stderr_text;
  for (const auto& [file, time] : ModificationTimes(run)) {
    if (file.rfind("scan/", 0) == 0 || file.rfind("renders/orbit/", 0) == 0) {
      EXPECT_EQ(finished_times.at(file), time) << file;
    }
  }
}

TEST_F(RunCommandTest, WrongExcludedCameraNameIsRefused) {
  testing::TempDir out;
  const testing::CommandResult result =
      RunConfluent({"run", Capture(), "--out", out / "run", "--exclude-camera", "cam99"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.stderr_text.find("cam99"), std::string::npos) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("cam00"), std::string::npos) << "the message should list the known cameras";
}

TEST_F(RunCommandTest, OutOfRangeRefineIterationsIsAUsageError) {
  testing::TempDir out;
  const testing::CommandResult result =
      RunConfluent({"run", Capture(), "--out", out / "run", "--refine-iterations", "0"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.stderr_text.find("--refine-iterations"), std::string::npos) << result.stderr_text;
  EXPECT_FALSE(fs::exists(out / "run/masks")) << "no work before the options are checked";
}

TEST_F(RunCommandTest, CorruptImageMidwayStopsWithItsNameAndKeepsEarlierFrames) {
  testing::TempDir out;
  const std::string capture = out / "capture";
  fs::copy(Capture(), capture, fs::copy_options::recursive);
  const std::string broken = capture + "/images/cam01/000005.png";
  fs::resize_file(broken, 100);
  const std::string run = out / "run";
  const testing::CommandResult result = RunConfluent({"run", capture, "--out", run, "--exclude-camera", "holdout0"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.stderr_text.find("000005.png"), std::string::npos) << result.stderr_text;
  EXPECT_TRUE(fs::exists(run + "/masks/cam00/000000.png"));
  EXPECT_TRUE(fs::exists(run + "/run.json"));
}

TEST_F(RunCommandTest, ShorterCameraIsNamed) {
  testing::TempDir out;
  const std::string capture = out / "capture";
  fs::copy(Capture(), capture, fs::copy_options::recursive);
  fs::remove(capture + "/images/cam02/000009.png");
  const testing::CommandResult result = RunConfluent({"run", capture, "--out", out / "run"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.stderr_text.find("cam02"), std::string::npos) << result.stderr_text;
}

TEST_F(RunCommandTest, OpenScanIsRefused) {
  testing::TempDir out;
  // The studio scan with its first 200 triangles removed has holes.
  const std::string scan = out / "open.ply";
  std::ifstream in(Truth() + "/scan.ply", std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Rewrite the face count in the header: readers then stop early, leaving an open surface.
  const std::size_t at = text.find("element face ");
  ASSERT_NE(at, std::string::npos);
  const std::size_t end = text.find('\n', at);
  const int faces = std::stoi(text.substr(at + 13, end - at - 13));
  text.replace(at, end - at, "element face " + std::to_string(faces - 200));
  std::ofstream(scan, std::ios::binary) << text;
  const std::string run = out / "run";
  const testing::CommandResult result =
      RunConfluent({"run", Capture(), "--scan", scan, "--out", run, "--exclude-camera", "holdout0"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.stderr_text.find("open.ply"), std::string::npos) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("watertight"), std::string::npos) << result.stderr_text;
}

TEST_F(RunCommandTest, WriteFailureIsReportedAndFinishedFilesAreKept) {
  testing::TempDir out;
  const std::string run = out / "run";
  // A file-size limit of 64 KiB: the masks fit, the first animated scan does not (as on a full disk).
  const testing::CommandResult result = RunConfluent(RunArgs(run), "trap '' XFSZ; ulimit -f 128;");
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.stderr_text.find("error"), std::string::npos) << result.stderr_text;
  EXPECT_EQ(CountFiles(run + "/masks/cam00", ".png"), 10);
  // No partial file is left under a final name.
  for (const auto& entry : fs::recursive_directory_iterator(run)) {
    if (entry.path().extension() == ".ply") {
      EXPECT_EQ(RunConfluent({"mesh", "info", entry.path().string()}).exit_code, 0) << entry.path();
    }
  }
}

}  // namespace
}  // namespace confluent
