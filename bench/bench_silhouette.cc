// Silhouette extraction speed: 8 cameras at 1024x768 per frame (decoding excluded), on the
// threads the capture driver uses; and frame decoding from PNG, JPEG and video separately.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <random>
#include <thread>
#include <unistd.h>

#include "core/cv_interop.h"
#include "core/image_io.h"
#include "core/mesh_ops.h"
#include "core/video.h"
#include "silhouette/classify_kernel.h"
#include "silhouette/disk_morphology.h"
#include "silhouette/multiview.h"
#include "silhouette/overlap.h"
#include "silhouette/silhouette.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

constexpr int kWidth = 1024;
constexpr int kHeight = 768;
constexpr int kCameras = 8;

// A textured background (tiles, grain, gradient) with Gaussian noise.
Image MakePlate(unsigned seed) {
  Image plate(kWidth, kHeight, 3);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 2.0f);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const bool odd = ((x / 64) + (y / 48)) % 2;
      const float base = (odd ? 140.0f : 100.0f) + 10.0f * std::sin(0.3f * x + 0.2f * y) + 30.0f * y / kHeight;
      for (int c = 0; c < 3; ++c)
        plate.at<std::uint8_t>(x, y, c) =
            static_cast<std::uint8_t>(std::clamp(base + 8.0f * c + noise(rng), 0.0f, 255.0f));
    }
  return plate;
}

// The plate with a person-sized coloured blob (and a darker floor shadow), re-noised.
Image MakeFrame(const Image& plate, unsigned seed) {
  Image frame = plate;
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 2.0f);
  const float cx = kWidth * 0.5f, cy = kHeight * 0.45f;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const float dx = (x - cx) / 90.0f, dy = (y - cy) / 280.0f;
      const float sx = (x - cx - 120.0f) / 150.0f, sy = (y - cy - 290.0f) / 25.0f;
      for (int c = 0; c < 3; ++c) {
        float value = frame.at<std::uint8_t>(x, y, c);
        if (dx * dx + dy * dy < 1) value = c == 0 ? 190.0f : c == 1 ? 60.0f : 50.0f;
        else if (sx * sx + sy * sy < 1) value *= 0.6f;
        frame.at<std::uint8_t>(x, y, c) = static_cast<std::uint8_t>(std::clamp(value + noise(rng), 0.0f, 255.0f));
      }
    }
  return frame;
}

struct Rig8 {
  std::vector<Image> frames;
  std::vector<SilhouetteExtractor> extractors;
};

Rig8& SharedRig() {
  static Rig8* rig = [] {
    auto* r = new Rig8;
    for (int c = 0; c < kCameras; ++c) {
      const Image plate = MakePlate(10 + c);
      r->frames.push_back(MakeFrame(plate, 100 + c));
      const Image& frame = r->frames.back();
      r->extractors.emplace_back("cam" + std::to_string(c), std::vector<Image>{plate}, "plate",
                                 [&frame](int) { return frame; }, 1, 0, SilhouetteOptions{});
    }
    return r;
  }();
  return *rig;
}

// One multi-camera frame: cameras split over `threads` threads, as ExtractSilhouettes does.
void BM_Extract8Cameras1024x768(benchmark::State& state) {
  Rig8& rig = SharedRig();
  const int threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    auto work = [&](int t) {
      for (int c = t; c < kCameras; c += threads) {
        MaskSummary summary;
        benchmark::DoNotOptimize(rig.extractors[c].Extract(rig.frames[c], 0, &summary));
      }
    };
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
    work(0);
    for (auto& thread : pool) thread.join();
  }
  state.SetLabel("per multi-camera frame");
}
BENCHMARK(BM_Extract8Cameras1024x768)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// The stages of one camera: classification alone, and classification + clean-up.
void BM_ClassifyOneCamera(benchmark::State& state) {
  Rig8& rig = SharedRig();
  for (auto _ : state) benchmark::DoNotOptimize(rig.extractors[0].model().Classify(rig.frames[0]));
}
BENCHMARK(BM_ClassifyOneCamera)->Unit(benchmark::kMillisecond);

void BM_CleanMaskOneCamera(benchmark::State& state) {
  Rig8& rig = SharedRig();
  const Image raw = rig.extractors[0].model().Classify(rig.frames[0]);
  for (auto _ : state) benchmark::DoNotOptimize(CleanMask(raw, MaskCleanupOptions{}));
}
BENCHMARK(BM_CleanMaskOneCamera)->Unit(benchmark::kMillisecond);

void BM_SummarizeMaskOneCamera(benchmark::State& state) {
  Rig8& rig = SharedRig();
  const Image mask = CleanMask(rig.extractors[0].model().Classify(rig.frames[0]), MaskCleanupOptions{});
  for (auto _ : state) benchmark::DoNotOptimize(SummarizeMask(mask, 0.05, SilhouetteOptions{}));
}
BENCHMARK(BM_SummarizeMaskOneCamera)->Unit(benchmark::kMillisecond);

// A plate camera's highlights claimed inside the others' hull (run per camera-frame after the
// multi-view check): the hull stands in as the blob's mask grown by 12 pixels (a hull is larger
// than the silhouette).
void BM_ClaimHighlightsOneCamera(benchmark::State& state) {
  Rig8& rig = SharedRig();
  const Image mask = CleanMask(rig.extractors[0].model().Classify(rig.frames[0]), MaskCleanupOptions{});
  cv::Mat grown;
  cv::dilate(AsCvMat(mask), grown, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(25, 25)));
  const Image hull = ImageFromCvMat(grown);
  for (auto _ : state) {
    Image claimed = mask;
    benchmark::DoNotOptimize(
        ClaimHighlightsInsideHull(&claimed, rig.frames[0], rig.extractors[0].model(), hull, MultiViewOptions{}));
  }
}
BENCHMARK(BM_ClaimHighlightsOneCamera)->Unit(benchmark::kMillisecond);

// The multi-view work of one plate-capture frame, 10 cameras at 1024x768 around a person made
// of ellipsoids, on 2 threads: the confidences' check at 64 voxels (arg 0: all there was
// before session 61), and with it the loose hull of the others at 128 voxels against which
// the highlights are claimed (arg 1, ExtractSilhouettes now).
void BM_PlateFrameMultiView10Cameras(benchmark::State& state) {
  static const auto* scene = [] {
    auto* out = new std::pair<Rig, std::vector<Image>>();
    for (int i = 0; i < 10; ++i) {
      const double angle = 2 * M_PI * i / 10;
      out->first.cameras.push_back(LookAtCamera("cam" + std::to_string(i),
                                                Eigen::Vector3d(3.5 * std::cos(angle), 3.5 * std::sin(angle), 1.5),
                                                Eigen::Vector3d(0, 0, 0.95), kWidth, kHeight, 900));
    }
    // Legs, torso, head, an arm held out: (centre, radii).
    const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> parts = {
        {{-0.1, 0, 0.45}, {0.08, 0.08, 0.45}}, {{0.1, 0, 0.45}, {0.08, 0.08, 0.45}},
        {{0, 0, 1.2}, {0.2, 0.13, 0.35}},      {{0, 0, 1.68}, {0.1, 0.1, 0.12}},
        {{0.45, 0, 1.35}, {0.3, 0.05, 0.05}}};
    for (const Camera& camera : out->first.cameras) {
      cv::Mat mask(kHeight, kWidth, CV_8UC1, cv::Scalar(0));
      for (const auto& [centre, radii] : parts) {
        Mesh part = MakeUvSphere(1.0, 16, 24);
        for (int v = 0; v < part.vertices.rows(); ++v)
          part.vertices.row(v) = (part.vertices.row(v).transpose().cwiseProduct(radii) + centre).transpose();
        cv::bitwise_or(mask, AsCvMat(RasterizeClosedMesh(part, camera)), mask);
      }
      out->second.push_back(ImageFromCvMat(mask));
    }
    return out;
  }();
  MultiViewOptions options;
  options.threads = 2;
  MultiViewOptions check_only = options;
  check_only.grid_resolution = 64;
  for (auto _ : state) {
    std::vector<Image> masks = scene->second, hulls;
    benchmark::DoNotOptimize(CheckMultiView(scene->first, &masks, {}, check_only, &hulls));
    if (state.range(0) == 1) benchmark::DoNotOptimize(LooseHullsOfTheOthers(scene->first, masks, options));
  }
}
BENCHMARK(BM_PlateFrameMultiView10Cameras)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The multi-view correction's closing of a mask (a disk of 41 pixels: MultiViewOptions::hole_close
// at 1024 pixels of width), worked in the box around the mask (arg 1, as CheckMultiView does) or
// the same closing over the whole image (arg 0).
void BM_CloseByDisk41(benchmark::State& state) {
  Rig8& rig = SharedRig();
  const Image mask = CleanMask(rig.extractors[0].model().Classify(rig.frames[0]), MaskCleanupOptions{});
  const cv::Mat m = AsCvMat(mask);
  const int radius = 41;
  for (auto _ : state) {
    if (state.range(0) == 1) {
      benchmark::DoNotOptimize(CloseByDisk(m, radius));
    } else {
      cv::Mat closed;
      cv::morphologyEx(m, closed, cv::MORPH_CLOSE, Disk(radius), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT,
                       cv::Scalar(0));
      benchmark::DoNotOptimize(closed);
    }
  }
  state.SetLabel(state.range(0) == 1 ? "in the mask's box" : "whole image");
}
BENCHMARK(BM_CloseByDisk41)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The classification loop alone, per instruction set (0 baseline x86-64, 1 AVX2, 2 AVX-512),
// with a planar model of the plate's colours.
void BM_ClassifyKernel(benchmark::State& state) {
  const auto isa = static_cast<ClassifyIsa>(state.range(0));
  if (!ClassifyIsaSupported(isa)) {
    state.SkipWithError("instruction set not supported by this CPU");
    return;
  }
  Rig8& rig = SharedRig();
  const std::size_t pixels = static_cast<std::size_t>(kWidth) * kHeight;
  const Image plate = MakePlate(10);
  std::vector<std::uint8_t> planes(6 * pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    for (int c = 0; c < 3; ++c) planes[c * pixels + i] = std::max<std::uint8_t>(1, plate.data[3 * i + c]);
    planes[3 * pixels + i] = 24;   // 3 grey levels
    planes[4 * pixels + i] = 102;  // shadows down to 0.4
    planes[5 * pixels + i] = 10;   // highlights up to 1.3
  }
  ClassifyPlanes model{planes.data(), planes.data() + pixels, planes.data() + 2 * pixels,
                       planes.data() + 3 * pixels, planes.data() + 4 * pixels, planes.data() + 5 * pixels};
  std::vector<std::uint8_t> mask(pixels);
  for (auto _ : state) {
    ClassifyPixels(rig.frames[0].data.data(), model, pixels, ClassifyParams{}, mask.data(), isa);
    benchmark::DoNotOptimize(mask.data());
  }
}
BENCHMARK(BM_ClassifyKernel)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

void BM_ChromaKeyOneCamera(benchmark::State& state) {
  Rig8& rig = SharedRig();
  for (auto _ : state) benchmark::DoNotOptimize(ChromaKey(rig.frames[0], 0.2, ChromaKeyOptions{}));
}
BENCHMARK(BM_ChromaKeyOneCamera)->Unit(benchmark::kMillisecond);

// Decoding one 1024x768 frame.
struct DecodeFiles {
  std::string dir;
  std::string png, jpeg, mjpg_video, mp4_video;
  int video_frames = 50;
  ~DecodeFiles() {
    std::error_code ignored;
    if (!dir.empty()) fs::remove_all(dir, ignored);
  }
};

const DecodeFiles& SharedFiles() {
  static const std::unique_ptr<DecodeFiles> files = [] {
    auto f = std::make_unique<DecodeFiles>();
    f->dir = (fs::temp_directory_path() / ("bench_silhouette_" + std::to_string(::getpid()))).string();
    fs::create_directories(f->dir);
    const Image frame = MakeFrame(MakePlate(1), 2);
    f->png = f->dir + "/frame.png";
    f->jpeg = f->dir + "/frame.jpg";
    WriteImage(f->png, frame);
    WriteImage(f->jpeg, frame);
    f->mjpg_video = f->dir + "/video_mjpg.avi";
    f->mp4_video = f->dir + "/video_mp4v.mp4";
    for (const auto& [path, fourcc] : {std::pair{f->mjpg_video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G')},
                                        std::pair{f->mp4_video, cv::VideoWriter::fourcc('m', 'p', '4', 'v')}}) {
      cv::VideoWriter writer(path, fourcc, 25, cv::Size(kWidth, kHeight));
      for (int k = 0; k < f->video_frames; ++k) {
        Image moved = frame;
        std::rotate(moved.data.begin(), moved.data.begin() + 3 * 8 * k, moved.data.end());
        cv::Mat bgr;
        cv::cvtColor(AsCvMat(moved), bgr, cv::COLOR_RGB2BGR);
        writer.write(bgr);
      }
    }
    return f;
  }();
  return *files;
}

void BM_DecodePng1024x768(benchmark::State& state) {
  const DecodeFiles& files = SharedFiles();
  for (auto _ : state) benchmark::DoNotOptimize(ReadImage(files.png));
}
BENCHMARK(BM_DecodePng1024x768)->Unit(benchmark::kMillisecond);

void BM_DecodeJpeg1024x768(benchmark::State& state) {
  const DecodeFiles& files = SharedFiles();
  for (auto _ : state) benchmark::DoNotOptimize(ReadImage(files.jpeg));
}
BENCHMARK(BM_DecodeJpeg1024x768)->Unit(benchmark::kMillisecond);

// Sequential video decoding, per frame (reopening at the end is included, amortised).
void DecodeVideo(benchmark::State& state, const std::string& path, int frames) {
  std::unique_ptr<VideoReader> reader;
  int next = frames;
  for (auto _ : state) {
    if (next == frames) {
      reader = std::make_unique<VideoReader>(path);
      next = 0;
    }
    benchmark::DoNotOptimize(reader->ReadFrame(next++));
  }
}
void BM_DecodeVideoMjpeg1024x768(benchmark::State& state) {
  DecodeVideo(state, SharedFiles().mjpg_video, SharedFiles().video_frames);
}
BENCHMARK(BM_DecodeVideoMjpeg1024x768)->Unit(benchmark::kMillisecond);
void BM_DecodeVideoMpeg4_1024x768(benchmark::State& state) {
  DecodeVideo(state, SharedFiles().mp4_video, SharedFiles().video_frames);
}
BENCHMARK(BM_DecodeVideoMpeg4_1024x768)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace confluent

BENCHMARK_MAIN();
