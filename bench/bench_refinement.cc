// Refinement of one animated-scan frame, as `confluent run` does it after Confluent Motion: the
// silhouette refinement (18 rounds) and the photo-consistency refinement (5 rounds, without the
// 6 silhouette rounds that follow it in the run). Self-contained: a textured ~50K-vertex sphere
// of radius 0.4 m seen by 8 ring cameras at 1024x768 (about 4.3 mm per pixel, as the studio
// default), the start shrunk, shifted and bulged by a few millimetres. And the scan's own
// silhouette in one camera, as each refinement round draws it for every camera.

#include <benchmark/benchmark.h>

#include <cmath>

#include "core/mesh_ops.h"
#include "refine/photo_refinement.h"
#include "refine/silhouette_refinement.h"
#include "render/renderer.h"
#include "silhouette/overlap.h"
#include "silhouette/rim_silhouette.h"

namespace confluent {
namespace {

struct Scene {
  Mesh truth;
  RowMatrixX3d start;
  std::vector<Camera> cameras;
  std::vector<Image> images, masks;
};

const Scene& GetScene() {
  static const Scene scene = [] {
    Scene s;
    s.truth = MakeUvSphere(0.4, 160, 320);
    s.truth.colors.resize(s.truth.num_vertices(), 3);
    for (int v = 0; v < s.truth.num_vertices(); ++v) {
      const Eigen::Vector3d p = s.truth.vertices.row(v).transpose() / 0.4;
      const double a = std::sin(29.0 * p.x() + 3.0 * p.y()) * std::sin(23.0 * p.y() - 5.0 * p.z()) * std::sin(27.0 * p.z());
      s.truth.colors.row(v) << static_cast<float>(0.5 + 0.4 * a), 0.4f, static_cast<float>(0.5 - 0.4 * a);
    }
    MeshRenderer renderer;
    renderer.AddMesh(s.truth);
    RenderRequest request;
    request.shading.lit = false;
    request.silhouette = true;
    request.cull_back_faces = true;
    for (int k = 0; k < 8; ++k) {
      const double azimuth = 2.0 * M_PI * k / 8;
      const Eigen::Vector3d centre(4.8 * std::cos(azimuth), 4.8 * std::sin(azimuth), k % 2 ? 0.6 : -0.3);
      s.cameras.push_back(LookAtCamera("ring" + std::to_string(k), centre, Eigen::Vector3d::Zero(), 1024, 768, 1116.0));
      RenderResult result = renderer.Render(s.cameras.back(), request);
      s.images.push_back(std::move(result.color));
      s.masks.push_back(std::move(result.silhouette));
    }
    s.start = (0.99 * s.truth.vertices).rowwise() + Eigen::RowVector3d(0.004, -0.002, 0.0);
    for (int v = 0; v < s.truth.num_vertices(); ++v) {
      const Eigen::Vector3d direction = s.truth.vertices.row(v).transpose().normalized();
      if (direction.x() > 0.5) s.start.row(v) += (0.006 * (direction.x() - 0.5) / 0.5) * direction.transpose();
    }
    return s;
  }();
  return scene;
}

void BM_SilhouetteRefineFrame(benchmark::State& state) {
  const Scene& scene = GetScene();
  const SilhouetteRefiner refiner(scene.truth);
  for (auto _ : state) benchmark::DoNotOptimize(refiner.Refine(scene.start, scene.cameras, scene.masks));
  state.counters["vertices"] = scene.truth.num_vertices();
}

void BM_PhotoRefineFrame(benchmark::State& state) {
  const Scene& scene = GetScene();
  PhotoRefinementOptions options;
  options.flow_finest_scale = static_cast<int>(state.range(0));
  options.rounds = static_cast<int>(state.range(1));
  options.full_resolution_rounds = static_cast<int>(state.range(2));
  const PhotoRefiner refiner(scene.truth, options);
  PhotoRefinementSummary summary;
  for (auto _ : state) benchmark::DoNotOptimize(refiner.Refine(scene.start, scene.cameras, scene.images, &summary));
  state.counters["vertices"] = scene.truth.num_vertices();
  state.counters["flow_px_first"] = summary.first_flow_px;
  state.counters["flow_px_last"] = summary.last_flow_px;
}

// Argument 0: every facing triangle filled (RasterizeClosedMesh); 1: the rim edges' winding
// fill (RimSilhouetteRasterizer), the refinement's since 2026-11-26.
void BM_ScanSilhouetteOneCamera(benchmark::State& state) {
  const Scene& scene = GetScene();
  Mesh posed = scene.truth;
  posed.vertices = scene.start;
  const RimSilhouetteRasterizer rim(posed.faces);
  for (auto _ : state)
    benchmark::DoNotOptimize(state.range(0) ? rim.Rasterize(posed.vertices, scene.cameras[1])
                                            : RasterizeClosedMesh(posed, scene.cameras[1]));
  state.counters["faces"] = posed.num_faces();
}

BENCHMARK(BM_ScanSilhouetteOneCamera)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SilhouetteRefineFrame)->Unit(benchmark::kMillisecond)->UseRealTime();
// Arguments: the flow's finest pyramid level (1, the default: half resolution; 0: full), the
// rounds (default 5) and how many of the last ones measure at full resolution (default 2 since
// 2026-12-06; `run --photo-rounds 8 --photo-full-res-rounds 3`). The sphere is small in the images,
// which understates the full-resolution rounds' cost on a body: bench_photo_studio.
BENCHMARK(BM_PhotoRefineFrame)
    ->Args({1, 5, 0})
    ->Args({1, 5, 1})
    ->Args({1, 5, 2})
    ->Args({0, 5, 0})
    ->Args({1, 8, 3})
    ->Args({0, 8, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace confluent

BENCHMARK_MAIN();
