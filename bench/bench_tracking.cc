// Tracking speed: 8 cameras at 1024x768, the first frame's initialisation and the frames after.
//
// Masks come from the studio capture's ground truth when $CONFLUENT_BENCH_TRACK_MASKS names a
// folder <dir>/<cam>/<frame>.png and $CONFLUENT_BENCH_TRACK_CAPTURE the capture (intri/extri);
// otherwise they are rendered from the template itself in a moving pose (self-contained).
// Counters: iterations per frame (LM iterations of all stages).

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "calib/capture.h"
#include "core/image_io.h"
#include "silhouette/overlap.h"
#include "tracking/tracker.h"

namespace confluent {
namespace {

Camera LookAt(const std::string& name, const Eigen::Vector3d& center, const Eigen::Vector3d& target) {
  Camera camera;
  camera.name = name;
  camera.width = 1024;
  camera.height = 768;
  camera.K << 1126.4, 0, 511.5, 0, 1126.4, 383.5, 0, 0, 1;
  const Eigen::Vector3d z = (target - center).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  camera.rotation.row(0) = x.transpose();
  camera.rotation.row(1) = y.transpose();
  camera.rotation.row(2) = z.transpose();
  camera.translation = -camera.rotation * center;
  return camera;
}

struct Sequence {
  Rig rig;
  std::vector<std::vector<Image>> masks;  // [frame][camera]
};

Sequence MakeSequence(int frames) {
  Sequence s;
  const char* capture_dir = std::getenv("CONFLUENT_BENCH_TRACK_CAPTURE");
  const char* masks_dir = std::getenv("CONFLUENT_BENCH_TRACK_MASKS");
  if (capture_dir && masks_dir) {
    CaptureOptions options;
    options.check_every_image_header = false;
    const Capture capture = Capture::Open(capture_dir, options);
    for (const Camera& camera : capture.rig().cameras)
      if (camera.name.rfind("holdout", 0) != 0) s.rig.cameras.push_back(camera);
    for (int f = 0; f < frames; ++f) {
      std::vector<Image> row;
      for (const Camera& camera : s.rig.cameras) {
        char name[32];
        std::snprintf(name, sizeof name, "/%06d.png", f);
        Image m = ReadImage(std::string(masks_dir) + "/" + camera.name + name);
        Image mask(m.width, m.height, 1);
        for (int i = 0; i < m.width * m.height; ++i) mask.data[i] = m.data[i * m.channels] >= 128 ? 255 : 0;
        row.push_back(std::move(mask));
      }
      s.masks.push_back(std::move(row));
    }
    return s;
  }
  for (int i = 0; i < 8; ++i) {
    const double a = 2 * M_PI * i / 8;
    s.rig.cameras.push_back(LookAt("cam" + std::to_string(i), Eigen::Vector3d(3.8 * std::sin(a), 3.8 * std::cos(a), 1.6 + 0.5 * (i % 2)),
                                   Eigen::Vector3d(0, 0, 1.0)));
  }
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.75);
  for (int f = 0; f < frames; ++f) {
    const double t = f / 25.0;
    TemplatePose pose;
    pose.root_rotation = Eigen::Vector3d(0, 0, 0.8 * t);
    pose.root_translation = Eigen::Vector3d(0.1 * t, 0, 0);
    pose.dofs[kJointLeftShoulder] = {0.5 * std::sin(4 * t), 1.2 * t, 0};
    pose.dofs[kJointRightShoulder] = {-0.5 * std::sin(4 * t), -1.0 * t, 0};
    pose.dofs[kJointLeftElbow] = {0.3 + 0.6 * t, 0, 0};
    pose.dofs[kJointLeftHip] = {0.6 * std::sin(3 * t), 0, 0};
    pose.dofs[kJointLeftKnee] = {-0.8 * t, 0, 0};
    const Mesh mesh = body.PosedMesh(shape, pose);
    std::vector<Image> row;
    for (const Camera& camera : s.rig.cameras) row.push_back(RasterizeSilhouette(mesh, camera, 1));
    s.masks.push_back(std::move(row));
  }
  return s;
}

// 16 frames; 26 for the shape learned over the first frames (TrackerOptions::shape_samples: the
// first frame and every 5th after it, 6 in all).
const Sequence& GetSequence() {
  static const Sequence sequence = MakeSequence(16);
  return sequence;
}
const Sequence& GetLongSequence() {
  static const Sequence sequence = MakeSequence(26);
  return sequence;
}

// Distance transforms and contour rays of one frame (8 cameras), at the per-frame fit's scale.
void BM_PrepareObservations(benchmark::State& state) {
  const Sequence& s = GetSequence();
  const SilhouetteFitOptions fit = TrackerOptions().fit;
  for (auto _ : state) {
    const SilhouetteObservations observations(s.rig, s.masks[1], {}, fit.downscale, fit.max_contour_points,
                                              fit.automatic_width);
    benchmark::DoNotOptimize(observations.num_used_cameras());
  }
}
BENCHMARK(BM_PrepareObservations)->Unit(benchmark::kMillisecond);

// The first frame: placement from the visual hull, the shape-and-pose fits, the girths tried
// grown where the fit is poor, the skirt tried, lost limbs searched.
void BM_InitializeFirstFrame(benchmark::State& state) {
  const Sequence& s = GetSequence();
  for (auto _ : state) {
    Tracker tracker(s.rig, {});
    const TrackedFrame result = tracker.Initialize(0, s.masks[0]);
    benchmark::DoNotOptimize(result.mean_iou);
  }
}
BENCHMARK(BM_InitializeFirstFrame)->Unit(benchmark::kSecond)->Iterations(1);

// The same with the shape learned over the first frames, as `confluent run` does: frames 1-25
// tracked ahead, the shape fitted on 6 of them, the first frame fitted again.
void BM_InitializeFirstFrameLearningTheShape(benchmark::State& state) {
  const Sequence& s = GetLongSequence();
  for (auto _ : state) {
    Tracker tracker(s.rig, {});
    tracker.UseLaterMasks([&s](int frame) {
      return frame < static_cast<int>(s.masks.size()) ? s.masks[frame] : std::vector<Image>();
    });
    const TrackedFrame result = tracker.Initialize(0, s.masks[0]);
    benchmark::DoNotOptimize(result.mean_iou);
  }
}
BENCHMARK(BM_InitializeFirstFrameLearningTheShape)->Unit(benchmark::kSecond)->Iterations(1);

// One full tracking step (prediction, observation preparation, fit, overlap check).
void BM_TrackFrame(benchmark::State& state) {
  const Sequence& s = GetSequence();
  Tracker tracker(s.rig, {});
  tracker.Initialize(0, s.masks[0]);
  std::size_t frame = 1;
  double iterations = 0, fit_seconds = 0;
  long count = 0;
  for (auto _ : state) {
    if (frame >= s.masks.size()) {
      state.PauseTiming();
      tracker.Initialize(0, s.masks[0]);
      frame = 1;
      state.ResumeTiming();
    }
    const TrackedFrame result = tracker.Track(static_cast<int>(frame), s.masks[frame]);
    iterations += result.fit.iterations;
    fit_seconds += result.fit.seconds;
    ++count;
    ++frame;
  }
  state.counters["iterations_per_frame"] = iterations / std::max(1L, count);
  state.counters["fit_ms_per_frame"] = 1000.0 * fit_seconds / std::max(1L, count);
}
BENCHMARK(BM_TrackFrame)->Unit(benchmark::kMillisecond)->MinTime(5.0);

}  // namespace
}  // namespace confluent

BENCHMARK_MAIN();
