// Backgrounds learned without a plate (LearnBackgroundsWithoutPlates, silhouette/plate_free.h),
// as `confluent silhouettes` runs it on a capture without its background/ folder: the demo's
// capture (the default studio preset: 8 used and 2 held-out cameras at 1024x768) synthesised once
// for $CONFLUENT_BENCH_PLATE_FREE_FRAMES frames (default 31, the number of frames the learning
// samples) into a temporary folder; synthesis and frame decoding are not timed.
//
// The argument is the number of threads. One iteration learns the 10 cameras' backgrounds from
// 31 frames each: the first estimates, then two rounds of masks, multi-view check, occupancy
// and background.

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/scratch_folder.h"
#include "calib/capture.h"
#include "core/image.h"
#include "silhouette/plate_free.h"
#include "silhouette/silhouette.h"
#include "studio/presets.h"
#include "studio/synth.h"

namespace confluent {
namespace {

// The sampled frames of every camera, and the rig.
struct Workspace {
  Rig rig;
  std::vector<std::vector<Image>> frames;
};

const Workspace& GetWorkspace() {
  static const ScratchFolder scratch("confluent_bench_plate_free_");
  static const Workspace workspace = [] {
    const char* frames = std::getenv("CONFLUENT_BENCH_PLATE_FREE_FRAMES");
    StudioSynthOptions options = StudioSynthPreset("default", "default");
    options.motion.num_frames = frames ? std::atoi(frames) : 31;
    options.capture_dir = (scratch.path / "capture").string();
    options.ground_truth_dir = (scratch.path / "capture_gt").string();
    SynthesizeCapture(options);
    const Capture capture = Capture::Open(options.capture_dir);
    Workspace w;
    w.rig = capture.rig();
    const std::vector<int> samples = EvenFrameSample(capture.num_frames(), BackgroundModelOptions{}.learned_frames);
    w.frames.resize(capture.num_cameras());
    for (int c = 0; c < capture.num_cameras(); ++c)
      for (int k : samples) w.frames[c].push_back(ToRgb8(capture.ReadFrame(c, k)));
    return w;
  }();
  return workspace;
}

void BM_LearnBackgroundsWithoutPlates(benchmark::State& state) {
  const Workspace& workspace = GetWorkspace();
  const int threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(LearnBackgroundsWithoutPlates(
        workspace.rig, workspace.frames, std::vector<BackgroundModel>(workspace.rig.size()), BackgroundModelOptions{},
        MaskCleanupOptions{}, PlateFreeOptions{}, nullptr, threads));
  }
  state.SetLabel(std::to_string(workspace.rig.size()) + " cameras, " + std::to_string(workspace.frames[0].size()) +
                 " frames of " + std::to_string(workspace.frames[0][0].width) + "x" +
                 std::to_string(workspace.frames[0][0].height));
}
BENCHMARK(BM_LearnBackgroundsWithoutPlates)->Arg(1)->Arg(2)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace confluent

BENCHMARK_MAIN();
