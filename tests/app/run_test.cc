// End-to-end tests of `confluent run` and `confluent evaluate` on the tiny studio capture:
// outputs against the studio's ground truth, resuming after a SIGKILL in every stage (same
// outputs, finished files untouched, no partial file under a final name), a full disk, and bad
// input (clear message, non-zero exit, finished output kept).

#include <gtest/gtest.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <nlohmann/json.hpp>

#include "core/image_io.h"
#include "core/mesh_io.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;
using testing::RunConfluent;
using testing::CountFiles;

// Refinement keyframes at frames 0, 3, 6 and 9: a run resumed at frame 1, 4 or 8 replays the
// frames since the keyframe (pipeline/frame_refinement.h).
std::vector<std::string> RunArgs(const std::string& capture, const std::string& run) {
  return {"run", capture, "--out", run, "--exclude-camera", "holdout0", "--exclude-camera", "holdout1",
          "--render-width", "160", "--render-height", "120", "--refine-keyframes", "3"};
}

// Makes the suite's tiny capture (4 ring + 2 held-out cameras, 160x120, 10 frames at 12.5 fps) in
// `root`/capture, its ground truth in `root`/capture_gt.
void MakeCapture(const std::string& root) {
  const testing::CommandResult synth =
      RunConfluent({"synth", "--preset", "tiny", "--fps", "12.5", "--out", root + "/capture"});
  ASSERT_EQ(synth.exit_code, 0) << synth.stderr_text;
}

// Makes the uninterrupted run of RunArgs in `root`/reference_run; returns what it printed.
std::string MakeReferenceRun(const std::string& root) {
  const testing::CommandResult result = RunConfluent(RunArgs(root + "/capture", root + "/reference_run"));
  EXPECT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
  return result.stdout_text + result.stderr_text;
}

// Under ctest, the capture and the reference run are made once for every test of the suite by
// the RunCommandReference fixture (tests/CMakeLists.txt), in $CONFLUENT_RUN_REFERENCE; the test
// binary run alone makes its own.
class RunCommandTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const char* shared = std::getenv("CONFLUENT_RUN_REFERENCE");
    if (shared != nullptr && *shared != '\0') {
      root_ = shared;
      ASSERT_TRUE(fs::exists(root_ + "/reference_run/run.json") && fs::exists(root_ + "/reference_run.log"))
          << "the RunCommandReference fixture left no run in " << root_;
      return;
    }
    dir_ = new testing::TempDir();
    root_ = dir_->path();
    MakeCapture(root_);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string Capture() { return root_ + "/capture"; }
  static std::string Truth() { return root_ + "/capture_gt"; }
  static std::vector<std::string> RunArgs(const std::string& run) { return confluent::RunArgs(Capture(), run); }
  // An uninterrupted run of RunArgs, made once for the suite (do not modify it).
  static const std::string& ReferenceRun() {
    static const std::string run = [] {
      if (dir_ != nullptr && !fs::exists(root_ + "/reference_run.log")) {
        std::ofstream(root_ + "/reference_run.log") << MakeReferenceRun(root_);
      }
      return root_ + "/reference_run";
    }();
    return run;
  }
  // What the reference run printed.
  static std::string ReferenceRunLog() {
    ReferenceRun();
    std::ifstream in(root_ + "/reference_run.log");
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  static testing::TempDir* dir_;
  static std::string root_;
};
testing::TempDir* RunCommandTest::dir_ = nullptr;
std::string RunCommandTest::root_;

// The RunCommandReference fixture of ctest: the capture and the reference run, made into
// $CONFLUENT_RUN_REFERENCE_OUT for the RunCommandTest suite's processes to share.
TEST(RunCommandReference, MakesTheCaptureAndTheUninterruptedRun) {
  const char* out = std::getenv("CONFLUENT_RUN_REFERENCE_OUT");
  if (out == nullptr || *out == '\0') GTEST_SKIP() << "made only as ctest's RunCommandReference fixture";
  const std::string root = out;
  fs::remove_all(root);
  fs::create_directories(root);
  MakeCapture(root);
  const std::string log = MakeReferenceRun(root);
  ASSERT_FALSE(HasFailure());
  std::ofstream(root + "/reference_run.log") << log;
}

std::map<std::string, fs::file_time_type> ModificationTimes(const std::string& root) {
  std::map<std::string, fs::file_time_type> times;
  for (const auto& entry : fs::recursive_directory_iterator(root))
    if (entry.is_regular_file()) times[fs::relative(entry.path(), root).string()] = entry.last_write_time();
  return times;
}

bool IsTemporary(const fs::path& path) { return path.filename().string().rfind(".tmp", 0) == 0; }

// Drops every "seconds" and "cpu_seconds" member (time of a step) from a JSON value.
void DropSeconds(nlohmann::json* json) {
  if (json->is_object()) {
    json->erase("seconds");
    json->erase("cpu_seconds");
    for (auto& [key, value] : json->items()) DropSeconds(&value);
  } else if (json->is_array()) {
    for (auto& value : *json) DropSeconds(&value);
  }
}

// The outputs of a run folder, for comparing two runs: relative path -> contents. Everything the
// run computes is deterministic (the tiny run twice, and a run killed and resumed 13 times, gave
// the same bytes; threads only split work by camera or by independent rows), so files are
// compared byte for byte, except what records the run rather than its result:
// - timings.csv (wall-clock seconds) is left out;
// - tracking/<frame>.json and poses.json hold the tracking time of each frame ("seconds"):
//   compared as JSON without those members;
// - run.json: without options.out (the folder's own name).
std::map<std::string, std::string> RunOutputs(const std::string& root) {
  std::map<std::string, std::string> outputs;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file() || IsTemporary(entry.path())) continue;
    const std::string file = fs::relative(entry.path(), root).string();
    if (file == "timings.csv") continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (file == "poses.json" || file.rfind("tracking/", 0) == 0 || file == "run.json") {
      nlohmann::json json = nlohmann::json::parse(bytes);
      DropSeconds(&json);
      if (file == "run.json") json["options"].erase("out");
      bytes = json.dump();
    }
    outputs[file] = bytes;
  }
  return outputs;
}

// The rows of `stage` in the run's timings.csv: one per frame (or step) that the stage computed.
int TimingRows(const std::string& run, const std::string& stage) {
  std::ifstream in(run + "/timings.csv");
  int rows = 0;
  for (std::string line; std::getline(in, line);) rows += line.rfind(stage + ",", 0) == 0;
  return rows;
}

// Every file under its final name in `root` reads back (PLY, PNG, JSON); temporaries are named
// .tmp<pid>_<name> and are the only files allowed to be partial.
void ExpectEveryFileParses(const std::string& root, const std::string& when) {
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    const fs::path& path = entry.path();
    const std::string name = path.filename().string();
    if (IsTemporary(path)) {
      EXPECT_NE(name.find('_'), std::string::npos) << when << ": " << path;
      EXPECT_EQ(name.find_first_not_of("0123456789", 4), name.find('_')) << when << ": " << path;
      continue;
    }
    const std::string extension = path.extension().string();
    try {
      if (extension == ".ply") ReadMesh(path.string());
      if (extension == ".png") ReadImage(path.string());
      if (extension == ".json") {
        EXPECT_FALSE(nlohmann::json::parse(std::ifstream(path)).is_null()) << path;
      }
    } catch (const std::exception& error) {
      ADD_FAILURE() << when << ": " << path << " is partial or corrupt: " << error.what();
    }
  }
}

TEST_F(RunCommandTest, CaptureToThreeDVideoAndHeldOutEvaluation) {
  testing::TempDir out;
  const std::string run = out / "run";  // evaluate writes into it
  fs::copy(ReferenceRun(), run, fs::copy_options::recursive);
  const std::string printed = ReferenceRunLog();
  for (const char* file : {"run.json", "timings.csv", "poses.json", "motion.bvh", "correspondences.json",
                           "template_reference.ply"})
    EXPECT_TRUE(fs::exists(fs::path(run) / file)) << file;
  EXPECT_EQ(CountFiles(run + "/masks/holdout0", ".png"), 10);  // held-out cameras get masks too
  EXPECT_EQ(CountFiles(run + "/template", ".ply"), 10);
  EXPECT_EQ(CountFiles(run + "/scan", ".ply"), 10);
  EXPECT_EQ(CountFiles(run + "/renders/orbit", ".png"), 10);
  // Every frame went through the silhouette and then the photo-consistency refinement.
  EXPECT_NE(printed.find("photo refinement: mean flow between neighbouring cameras"), std::string::npos) << printed;
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
  // The silhouettes' confidence: the 10 frames of the 4 tracking cameras checked (the sample is
  // the whole of so short a run), and shown in the report.
  const nlohmann::json trust = nlohmann::json::parse(std::ifstream(run + "/mask_confidence.json"));
  EXPECT_EQ(trust["source"], "sample");
  EXPECT_EQ(trust["camera_frames"], 40);
  EXPECT_GT(trust["mean_confidence"].get<double>(), 0.8);
  std::ifstream report_file(run + "/report.html");
  const std::string report((std::istreambuf_iterator<char>(report_file)), std::istreambuf_iterator<char>());
  EXPECT_NE(report.find("<h2>Silhouette confidence</h2>"), std::string::npos);
  for (const auto& camera : trust["cameras"])  // the held-out cameras are kept out of the check
    EXPECT_EQ(camera["checked"].get<int>(), camera["name"].get<std::string>().rfind("holdout", 0) == 0 ? 0 : 10)
        << camera.dump();
  EXPECT_NE(report.find("<td>not checked (held out)</td>"), std::string::npos);

  // The views are scored over the held-out cameras' clean plates (the synthetic capture has them),
  // with the input colours matched to each held-out camera's response and the outline matted.
  // Without the match the colours inside change; over black with a binary outline, only the
  // pixels outside the rendered silhouette:
  // the union's PSNR moves, the PSNR inside both silhouettes does not.
  EXPECT_EQ(metrics["background"], "clean plate");
  EXPECT_EQ(metrics["colour_matched"], true);
  // From here on without CAPTURE and --heldout: run.json records both.
  auto evaluate_with = [&](const std::vector<std::string>& options) {
    std::vector<std::string> args = {"evaluate", "--run", run, "--masks", Truth() + "/masks", "--side-by-side-every", "0"};
    args.insert(args.end(), options.begin(), options.end());
    const testing::CommandResult result = RunConfluent(args);
    EXPECT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
    return nlohmann::json::parse(std::ifstream(run + "/metrics.json"));
  };
  EXPECT_EQ(metrics["edge_softness_px"], 0.5);
  const nlohmann::json from_run = evaluate_with({"--gt-meshes", Truth() + "/meshes"});
  EXPECT_EQ(from_run["rows"], metrics["rows"]);
  EXPECT_EQ(from_run["scan"], metrics["scan"]);
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
  // The scan from its baked UV atlas, through H.264: the same outline (MeshRenderer instead of the
  // texturer's rasteriser), colours close to the projective ones; the template is untouched.
  const nlohmann::json atlas = evaluate_with({"--texture", "atlas", "--atlas-size", "256", "--atlas-samples", "2"});
  EXPECT_EQ(atlas["texturing"].get<std::string>().rfind("scan: atlas 256 px", 0), 0u) << atlas["texturing"];
  EXPECT_NEAR(atlas["scan"]["iou_mean"].get<double>(), metrics["scan"]["iou_mean"].get<double>(), 5e-3);
  EXPECT_GT(atlas["scan"]["psnr_inside_db_mean"].get<double>(), metrics["scan"]["psnr_inside_db_mean"].get<double>() - 3.0);
  EXPECT_EQ(atlas["template"], metrics["template"]);
  EXPECT_TRUE(fs::exists(run + "/evaluation/atlas_holdout0.mp4"));
}

// A chain of runs in one folder, each killed (SIGKILL, through the CONFLUENT_KILL_AT hook of
// core/atomic_file.h) at a chosen file: after its temporary is complete, before the rename. The
// next run resumes where the previous one stopped, so every stage is hit at least twice:
// silhouettes, tracking (and its aggregate poses.json), correspondences (the registration's
// reference template, then the correspondences), deform with the silhouette and photo
// refinement (they write only scan/<frame>.ply, at the end of each frame), render (frames, then
// the video). After each kill: the file is not under its final name, every final file parses,
// and the only temporaries are the killed process's (the next run removes them). No run
// rewrites a file that existed before it, except the by-design ones (kRewritten). The last run
// completes and its outputs equal an uninterrupted run's (RunOutputs).
TEST_F(RunCommandTest, KilledInEveryStageResumesToTheUninterruptedOutputs) {
  const auto reference = RunOutputs(ReferenceRun());
  ASSERT_EQ(CountFiles(ReferenceRun() + "/scan", ".ply"), 10);
  testing::TempDir out;
  const std::string run = out / "run";
  // Rewritten by every run by design: the timing log, and poses.json and motion.bvh, which the
  // tracking stage regenerates over every tracked frame (all shards) each time it ends.
  const std::set<std::string> kRewritten = {"timings.csv", "poses.json", "motion.bvh"};
  struct KillPoint {
    std::string file;       // killed before this file's rename (its 1st write in that run)
    std::string unfinished;  // a file of the same, unfinished, frame or step that is written
                             // first and so is recomputed by the resume ("" when none)
  };
  const std::vector<KillPoint> kills = {
      // silhouettes: cameras run in parallel from frame 0, holdout1 (the last camera) starts
      // only after cam00, cam02, cam03 and holdout0 finish, long after cam01 reaches frame 3.
      {"masks/cam01/000003.png", ""},
      {"masks/holdout1/000009.png", ""},
      // tracking: the state file is written last and marks the frame finished.
      {"tracking/000002.json", "template/000002.ply"},
      {"template/000006.ply", ""},
      {"poses.json", ""},
      // correspondences
      {"template_reference.ply", ""},
      {"correspondences.json", "template_reference.ply"},
      // deform + silhouette refinement + photo refinement (one file per frame)
      {"scan/000001.ply", ""},
      {"scan/000004.ply", ""},
      {"scan/000008.ply", ""},
      // render: the deform stage draws each frame of the 3D video after its scan; killed there,
      // the render stage of the resume draws it from the scan file
      {"renders/orbit/000009.png", ""},
      {"renders/orbit.mp4", ""},
  };
  std::string previous_unfinished;
  for (const KillPoint& kill : kills) {
    const auto before = fs::exists(run) ? ModificationTimes(run) : std::map<std::string, fs::file_time_type>{};
    const testing::CommandResult result =
        RunConfluent(RunArgs(run), "export CONFLUENT_KILL_AT='" + kill.file + ":1';");
    ASSERT_EQ(result.exit_code, 128 + SIGKILL) << "not killed at " << kill.file << "\n" << result.stdout_text << result.stderr_text;
    EXPECT_FALSE(fs::exists(fs::path(run) / kill.file)) << kill.file;
    ExpectEveryFileParses(run, "killed at " + kill.file);
    std::set<std::string> temporary_pids;
    for (const auto& [file, time] : ModificationTimes(run)) {
      const std::string name = fs::path(file).filename().string();
      if (IsTemporary(name)) temporary_pids.insert(name.substr(4, name.find('_') - 4));
    }
    EXPECT_EQ(temporary_pids.size(), 1u) << "killed at " << kill.file << ": the temporaries of earlier runs are removed";
    const auto after = ModificationTimes(run);
    for (const auto& [file, time] : before) {
      if (kRewritten.count(file) || IsTemporary(fs::path(file).filename()) || file == previous_unfinished) continue;
      ASSERT_TRUE(after.count(file)) << file << " vanished in the run killed at " << kill.file;
      EXPECT_EQ(after.at(file), time) << file << " was rewritten by the run killed at " << kill.file;
    }
    previous_unfinished = kill.unfinished;
  }
  const auto before = ModificationTimes(run);
  const testing::CommandResult last = RunConfluent(RunArgs(run));
  ASSERT_EQ(last.exit_code, 0) << last.stdout_text << last.stderr_text;
  const auto after = ModificationTimes(run);
  for (const auto& [file, time] : before) {
    if (kRewritten.count(file) || IsTemporary(fs::path(file).filename()) || file == previous_unfinished) continue;
    ASSERT_TRUE(after.count(file)) << file;
    EXPECT_EQ(after.at(file), time) << file << " was rewritten by the last resume";
  }
  for (const auto& [file, time] : after) EXPECT_FALSE(IsTemporary(fs::path(file).filename())) << file;
  const auto resumed = RunOutputs(run);
  for (const auto& [file, bytes] : reference) {
    ASSERT_TRUE(resumed.count(file)) << file << " missing after the resumes";
    EXPECT_TRUE(resumed.at(file) == bytes) << file << " differs from the uninterrupted run's";
  }
  EXPECT_EQ(resumed.size(), reference.size());
  // Once finished, a run has nothing left to do.
  const testing::CommandResult again = RunConfluent(RunArgs(run));
  ASSERT_EQ(again.exit_code, 0) << again.stderr_text;
  for (const auto& [file, time] : ModificationTimes(run)) {
    if (kRewritten.count(file)) continue;
    EXPECT_EQ(after.at(file), time) << file << " was rewritten by a finished run";
  }
}

// Without keyframes (the default) consecutive frames are refined two at a time, each by its own
// refiner. Shards of odd length pair the frames differently from one run (frame 2 alone, then
// 3 with 4 ...), so their scans match the uninterrupted run's only if a frame's refinement is
// independent of the frame beside it. Both runs start from the reference run's silhouettes,
// tracking and correspondences (its scans and renders removed): only the deform stage runs.
TEST_F(RunCommandTest, FramesRefinedSideBySideMatchShardsThatPairThemDifferently) {
  testing::TempDir out;
  auto seed = [&](const std::string& run) {
    fs::copy(ReferenceRun(), run, fs::copy_options::recursive);
    for (const char* stage_output : {"scan", "renders", "timings.csv"}) fs::remove_all(fs::path(run) / stage_output);
  };
  auto args = [&](const std::string& run, const std::string& frames) {
    std::vector<std::string> command = {"run", Capture(), "--out", run, "--exclude-camera", "holdout0",
                                        "--exclude-camera", "holdout1", "--no-render"};
    if (!frames.empty()) command.insert(command.end(), {"--frames", frames});
    return command;
  };
  const std::string whole = out / "whole", sharded = out / "sharded";
  seed(whole);
  seed(sharded);
  const testing::CommandResult one = RunConfluent(args(whole, ""));
  ASSERT_EQ(one.exit_code, 0) << one.stdout_text << one.stderr_text;
  for (const std::string frames : {"0:3", "3:10"}) {
    const testing::CommandResult shard = RunConfluent(args(sharded, frames));
    ASSERT_EQ(shard.exit_code, 0) << frames << ": " << shard.stdout_text << shard.stderr_text;
  }
  ASSERT_EQ(CountFiles(whole + "/scan", ".ply"), 10);
  ASSERT_EQ(CountFiles(sharded + "/scan", ".ply"), 10);
  EXPECT_EQ(TimingRows(whole, "tracking"), 0) << "the tracking was the reference run's";
  EXPECT_EQ(TimingRows(whole, "deform"), 10);
  const auto expected = RunOutputs(whole), actual = RunOutputs(sharded);
  for (const auto& [file, bytes] : expected)
    if (file.rfind("scan/", 0) == 0) {
      ASSERT_TRUE(actual.count(file)) << file;
      EXPECT_TRUE(actual.at(file) == bytes) << file << " differs between the whole run and the shards";
    }
}

// The deform stage draws the 3D video's frames from the images it decoded for the photo
// refinement; the render stage, drawing them from the scan files, draws the same pixels.
TEST_F(RunCommandTest, VideoFramesDrawnWithTheScansEqualTheRenderStagesOwn) {
  const auto reference = RunOutputs(ReferenceRun());
  EXPECT_EQ(TimingRows(ReferenceRun(), "render"), 10);
  EXPECT_EQ(TimingRows(ReferenceRun(), "render_read"), 0) << "the reference's frames were drawn by the render stage";
  testing::TempDir out;
  const std::string run = out / "run";
  fs::copy(ReferenceRun(), run, fs::copy_options::recursive);
  fs::remove_all(run + "/renders");
  fs::remove(run + "/timings.csv");
  const testing::CommandResult result = RunConfluent(RunArgs(run));
  ASSERT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
  EXPECT_EQ(TimingRows(run, "render_read"), 10);
  const auto redrawn = RunOutputs(run);
  ASSERT_EQ(CountFiles(run + "/renders/orbit", ".png"), 10);
  for (const auto& [file, bytes] : reference)
    if (file.rfind("renders/", 0) == 0 && file != "renders/orbit.mp4") {
      ASSERT_TRUE(redrawn.count(file)) << file;
      EXPECT_TRUE(redrawn.at(file) == bytes) << file << " differs from the frame the deform stage drew";
    }
}

// Scans missing here and there (frames 2, 5 and 9; refinement keyframes at 0, 3, 6 and 9) are
// recomputed as the uninterrupted run wrote them: the deformation and the refinement carry on
// over the finished frames in between.
TEST_F(RunCommandTest, ScansMissingHereAndThereAreRewrittenAsOneRunWroteThem) {
  const auto reference = RunOutputs(ReferenceRun());
  testing::TempDir out;
  const std::string run = out / "run";
  fs::copy(ReferenceRun(), run, fs::copy_options::recursive);
  for (const char* frame : {"000002", "000005", "000009"}) ASSERT_TRUE(fs::remove(run + "/scan/" + frame + ".ply"));
  const testing::CommandResult result = RunConfluent(RunArgs(run));
  ASSERT_EQ(result.exit_code, 0) << result.stdout_text << result.stderr_text;
  const auto rewritten = RunOutputs(run);
  for (const char* frame : {"000002", "000005", "000009"}) {
    const std::string file = std::string("scan/") + frame + ".ply";
    ASSERT_TRUE(rewritten.count(file)) << file;
    EXPECT_TRUE(rewritten.at(file) == reference.at(file)) << file << " differs from the uninterrupted run's";
  }
}

// A hand-edited registration whose first tracked pose is malformed stops the deformation with
// the file and the key named; the finished scans stay.
TEST_F(RunCommandTest, MalformedFirstTrackedPoseInTheRegistrationIsNamed) {
  testing::TempDir out;
  const std::string run = out / "run";
  fs::copy(ReferenceRun(), run, fs::copy_options::recursive);
  ASSERT_TRUE(fs::remove(run + "/scan/000004.ply"));
  const std::string path = run + "/correspondences.json";
  nlohmann::json root;
  {
    std::ifstream in(path);
    root = nlohmann::json::parse(in);
  }
  ASSERT_TRUE(root.contains("template_registration"));
  root["template_registration"]["first_tracked_pose"] = "arms raised";
  std::ofstream(path) << root.dump();
  const testing::CommandResult result = RunConfluent(RunArgs(run));
  EXPECT_EQ(result.exit_code, 1) << result.stdout_text << result.stderr_text;
  EXPECT_NE(result.stderr_text.find(path + ": template_registration.first_tracked_pose: expected an object"),
            std::string::npos)
      << result.stderr_text;
  EXPECT_TRUE(fs::exists(run + "/scan/000003.ply"));
  EXPECT_FALSE(fs::exists(run + "/scan/000004.ply"));
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

TEST_F(RunCommandTest, OutOfRangeRefineKeyframesIsAUsageError) {
  testing::TempDir out;
  for (const char* value : {"0", "1001", "ten"}) {
    const testing::CommandResult result =
        RunConfluent({"run", Capture(), "--out", out / "run", "--refine-keyframes", value});
    EXPECT_EQ(result.exit_code, 2) << value;
    EXPECT_NE(result.stderr_text.find("--refine-keyframes"), std::string::npos) << value << ": " << result.stderr_text;
    EXPECT_FALSE(fs::exists(out / "run/masks")) << "no work before the options are checked";
  }
}

TEST_F(RunCommandTest, OutOfRangePhotoRoundsAndFitScalesAreUsageErrors) {
  testing::TempDir out;
  const std::vector<std::vector<std::string>> bad = {{"--photo-rounds", "0"},
                                                     {"--photo-rounds", "21"},
                                                     {"--photo-full-res-rounds", "-1"},
                                                     {"--photo-full-res-rounds", "6"},  // more than the 5 rounds
                                                     {"--photo-rounds", "3", "--photo-full-res-rounds", "4"},
                                                     {"--downscale", "-1"},
                                                     {"--downscale", "17"}};
  for (const std::vector<std::string>& options : bad) {
    std::vector<std::string> command = {"run", Capture(), "--out", out / "run"};
    command.insert(command.end(), options.begin(), options.end());
    const testing::CommandResult result = RunConfluent(command);
    EXPECT_EQ(result.exit_code, 2) << options.back();
    EXPECT_NE(result.stderr_text.find(options[options.size() - 2]), std::string::npos) << result.stderr_text;
    EXPECT_FALSE(fs::exists(out / "run/masks")) << "no work before the options are checked";
  }
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

// A file-size limit stands in for a full disk: the app ignores SIGXFSZ, so the write fails with
// EFBIG and the run stops with one message naming the file.
TEST_F(RunCommandTest, WriteFailureIsReportedAndFinishedFilesAreKept) {
  testing::TempDir out;
  const std::string run = out / "run";
  // 256 blocks: 128 KiB in dash's 512-byte blocks (256 KiB in bash's 1024-byte ones). The masks,
  // the tracking (posed templates of 80 KiB, poses.json of 68 KiB) and the correspondences fit,
  // the first animated scan (290 KiB) does not.
  const testing::CommandResult result = RunConfluent(RunArgs(run), "ulimit -f 256;");
  EXPECT_EQ(result.exit_code, 1) << result.stderr_text;
  const std::string message = "confluent run: error: " + run + "/scan/000000.ply: write failed: file too large or disk full";
  const std::size_t at = result.stderr_text.find(message);
  EXPECT_NE(at, std::string::npos) << result.stderr_text;
  int messages = 0;
  for (std::size_t i = result.stderr_text.find("error:"); i != std::string::npos; i = result.stderr_text.find("error:", i + 1))
    ++messages;
  EXPECT_EQ(messages, 1) << "one message: " << result.stderr_text;
  EXPECT_EQ(CountFiles(run + "/masks/cam00", ".png"), 10);
  EXPECT_EQ(CountFiles(run + "/tracking", ".json"), 10);
  EXPECT_TRUE(fs::exists(run + "/correspondences.json"));
  EXPECT_EQ(CountFiles(run + "/scan", ".ply"), 0);
  // No partial file is left under a final name, and no temporary is left at all.
  ExpectEveryFileParses(run, "after the failed write");
  for (const auto& [file, time] : ModificationTimes(run)) EXPECT_FALSE(IsTemporary(fs::path(file).filename())) << file;

  // Space again: the run completes, as if it had never stopped.
  const testing::CommandResult resumed = RunConfluent(RunArgs(run));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.stdout_text << resumed.stderr_text;
  EXPECT_TRUE(RunOutputs(run) == RunOutputs(ReferenceRun()));
}

}  // namespace
}  // namespace confluent
