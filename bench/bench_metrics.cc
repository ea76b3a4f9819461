// Speed of the image-quality metrics that `confluent evaluate` computes for every held-out view
// (core/image_metrics.h): PSNR and SSIM of a 1024x768 rendering against the real image inside the
// union of the silhouettes (a person-sized ellipse, about 12% of the image). Read the *_median
// rows: time per call.

#include <benchmark/benchmark.h>

#include <random>

#include "core/image_metrics.h"

namespace confluent {
namespace {

constexpr int kWidth = 1024, kHeight = 768;

Image Noise(unsigned seed) {
  Image image(kWidth, kHeight, 3);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(0, 255);
  for (auto& v : image.data) v = static_cast<std::uint8_t>(value(rng));
  return image;
}

// An upright ellipse in the middle of the image, 200 x 600 px.
Image PersonMask() {
  Image mask(kWidth, kHeight, 1);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const double u = (x - kWidth / 2) / 100.0, v = (y - kHeight / 2) / 300.0;
      mask.at<std::uint8_t>(x, y) = u * u + v * v <= 1.0 ? 255 : 0;
    }
  return mask;
}

void BM_MaskedPsnr(benchmark::State& state) {
  const Image a = Noise(1), b = Noise(2), mask = PersonMask();
  for (auto _ : state) benchmark::DoNotOptimize(MaskedPsnr(a, b, mask));
}

void BM_MaskedSsim(benchmark::State& state) {
  const Image a = Noise(1), b = Noise(2), mask = PersonMask();
  for (auto _ : state) benchmark::DoNotOptimize(MaskedSsim(a, b, mask));
}

void BM_AbsoluteDifference(benchmark::State& state) {
  const Image a = Noise(1), b = Noise(2);
  for (auto _ : state) benchmark::DoNotOptimize(AbsoluteDifference(a, b));
}

#define CONFLUENT_METRICS_BENCH(name) \
  BENCHMARK(name)->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(5)->ReportAggregatesOnly(true)

CONFLUENT_METRICS_BENCH(BM_MaskedPsnr);
CONFLUENT_METRICS_BENCH(BM_MaskedSsim);
CONFLUENT_METRICS_BENCH(BM_AbsoluteDifference);

}  // namespace
}  // namespace confluent

BENCHMARK_MAIN();
