// The whole `confluent run` per frame, silhouettes through render, with the stage split: the
// demo's capture (the default studio preset: 8 used and 2 held-out cameras at 1024x768, the
// 50K-vertex scan), synthesised once for the first $CONFLUENT_BENCH_RUN_FRAMES frames (default
// 40: the tracker's lost-limb search makes frames 8-16 of this performance take 5-7 s each, so
// fewer frames would time that alone) into a temporary folder; synthesis is not timed.
// $CONFLUENT_BENCH_RUN_CAPTURE names an existing capture to run instead (e.g. a demo's
// DIR/capture, all of its frames).
//
// One iteration is one run into a fresh run folder. Counters, in seconds: `whole_per_frame`, the
// median over frames of everything timed per frame summed (silhouettes through render, with
// reading and writing), and `whole_mean_per_frame` its mean (refinement keyframes and the first
// frames of silhouettes and tracking cost more); each timings.csv row's median per frame (e.g.
// render_read, render, render_write); `once`, the work done once per run (correspondences, the
// factorisations, the video).

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bench/scratch_folder.h"
#include "core/statistics.h"
#include "pipeline/run_capture.h"
#include "pipeline/run_folder.h"
#include "studio/presets.h"
#include "studio/synth.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

// The capture to run (given, or synthesised once per process) and the run folder.
struct Workspace {
  std::string capture;
  fs::path run;
};

const Workspace& GetWorkspace() {
  static const ScratchFolder scratch("confluent_bench_run_");
  static const Workspace workspace = [] {
    Workspace w;
    w.run = scratch.path / "run";
    if (const char* given = std::getenv("CONFLUENT_BENCH_RUN_CAPTURE")) {
      w.capture = given;
      return w;
    }
    const char* frames = std::getenv("CONFLUENT_BENCH_RUN_FRAMES");
    StudioSynthOptions options = StudioSynthPreset("default", "default");
    options.motion.num_frames = frames ? std::atoi(frames) : 40;
    options.capture_dir = (scratch.path / "capture").string();
    options.ground_truth_dir = (scratch.path / "capture_gt").string();
    SynthesizeCapture(options);
    w.capture = options.capture_dir;
    return w;
  }();
  return workspace;
}

void BM_RunPerFrame(benchmark::State& state) {
  const Workspace& workspace = GetWorkspace();
  std::map<std::string, std::map<int, double>> timings;  // stage -> frame -> seconds (-1: once per run)
  for (auto _ : state) {
    state.PauseTiming();
    fs::remove_all(workspace.run);
    state.ResumeTiming();
    RunOptions options;
    options.capture = workspace.capture;
    options.out = workspace.run.string();
    options.held_out = {"holdout0", "holdout1"};
    const TimingLog log(RunCapture(options, nullptr, nullptr, nullptr));
    timings.clear();
    for (const TimingLog::Row& row : log.rows()) timings[row.stage][row.frame] = row.seconds;
  }
  std::map<int, double> whole;
  for (const auto& [stage, frames] : timings) {
    std::vector<double> per_frame;
    for (const auto& [frame, seconds] : frames)
      if (frame >= 0) {
        per_frame.push_back(seconds);
        whole[frame] += seconds;
      }
    if (!per_frame.empty()) state.counters[stage] = Median(per_frame);
  }
  std::vector<double> whole_per_frame;
  for (const auto& [frame, seconds] : whole) whole_per_frame.push_back(seconds);
  state.counters["whole_per_frame"] = whole_per_frame.empty() ? 0.0 : Median(whole_per_frame);
  double sum = 0.0;
  for (double seconds : whole_per_frame) sum += seconds;
  state.counters["whole_mean_per_frame"] = whole_per_frame.empty() ? 0.0 : sum / whole_per_frame.size();
  state.counters["frames"] = static_cast<double>(whole.size());
  double once = 0.0;
  for (const auto& [stage, frames] : timings)
    if (frames.count(-1)) once += frames.at(-1);
  state.counters["once"] = once;
}

BENCHMARK(BM_RunPerFrame)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace confluent

BENCHMARK_MAIN();
