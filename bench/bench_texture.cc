// Speed of projective texturing (render/projective_texture.h): a 263K-triangle mesh textured
// from 8 ring cameras (1024x768 images) and rendered into a 1024x768 novel view.
//   BM_TextureSetFrame   per video frame: 8 depth maps (of the default ~20K-face proxy), feather
//                        maps, image copies
//   BM_TextureRender     per novel view: G-buffer rasterisation + read-back + CPU blending
//   BM_TextureFrame      both (one novel view per video frame, e.g. `confluent render`)
//   BM_TextureFrame4Views  SetFrame + 4 novel views (e.g. a viewer or several output paths);
//                          the time per view is a quarter of it
//   BM_TextureSetFrameHalfVisibility  SetFrame with visibility_scale = 0.5 (depth and feather
//                          maps at half resolution; not the default, it loses ~0.3 dB)
//   BM_TextureSetFrameFullMesh  SetFrame with depth maps of the full mesh (visibility_faces = 0)
//   BM_TextureFrameGlRaster  BM_TextureFrame with raster = kGl (depth maps and G-buffer drawn by
//                          GL, read back); the default (kAuto) rasterises on the CPU on a software
//                          GL such as llvmpipe
// Read the *_median rows.

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>

#include "core/mesh_ops.h"
#include "render/projective_texture.h"
#include "render/renderer.h"

namespace confluent {
namespace {

// A bumpy UV sphere of ~263K triangles, radius 0.9 m around (0, 0, 1), with vertex colours.
Mesh MakeBenchMesh() {
  Mesh mesh = MakeUvSphere(0.9, 258, 512);
  mesh.colors.resize(mesh.num_vertices(), 3);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
    const double bump = 1.0 + 0.03 * std::sin(7 * std::atan2(p.y(), p.x())) * std::sin(5 * std::acos(p.z() / 0.9));
    mesh.vertices.row(v) = (bump * p + Eigen::Vector3d(0, 0, 1)).transpose();
    mesh.colors.row(v) << 0.5f + 0.4f * static_cast<float>(std::sin(10 * p.x())), 0.4f,
        0.5f + 0.4f * static_cast<float>(std::cos(10 * p.z()));
  }
  return mesh;
}

Camera RingCamera(const std::string& name, double azimuth_deg, double height_m) {
  const double a = azimuth_deg * M_PI / 180.0;
  return LookAtCamera(name, Eigen::Vector3d(4.0 * std::cos(a), 4.0 * std::sin(a), height_m),
                      Eigen::Vector3d(0, 0, 1), 1024, 768, 1100.0);
}

struct Fixture {
  Mesh mesh = MakeBenchMesh();
  std::vector<Camera> cameras;
  std::vector<Image> images;
  std::unique_ptr<ProjectiveTexturer> texturer;
  Camera view = RingCamera("novel", 22.5, 1.8);
  Fixture() {
    MeshRenderer renderer;
    renderer.AddMesh(mesh);
    for (int i = 0; i < 8; ++i) {
      cameras.push_back(RingCamera("cam" + std::to_string(i), 45.0 * i, 1.5));
      images.push_back(renderer.Render(cameras.back()).color);
    }
    texturer = std::make_unique<ProjectiveTexturer>(mesh);
    texturer->SetFrame(mesh.vertices, cameras, images);
    texturer->Render(view);  // warm-up (shader compile, framebuffer)
  }
  // A texturer with other options, made on first use and kept under `name`.
  ProjectiveTexturer& Variant(const std::string& name, const ProjectiveTextureOptions& options) {
    std::unique_ptr<ProjectiveTexturer>& texturer_of_name = variants[name];
    if (!texturer_of_name) {
      texturer_of_name = std::make_unique<ProjectiveTexturer>(mesh, options);
      texturer_of_name->SetFrame(mesh.vertices, cameras, images);
    }
    return *texturer_of_name;
  }
  std::map<std::string, std::unique_ptr<ProjectiveTexturer>> variants;
};

// Never destroyed: tearing a GL context down from a static destructor can race the driver.
Fixture& GetFixture() {
  static Fixture* fixture = new Fixture;
  return *fixture;
}

// SetFrame with the mesh shifted a little every iteration (new vertices each video frame).
void SetFrameLoop(benchmark::State& state, ProjectiveTexturer& texturer) {
  Fixture& f = GetFixture();
  RowMatrixX3d moved = f.mesh.vertices;
  double offset = 0.0;
  for (auto _ : state) {
    offset = offset > 0.05 ? 0.0 : offset + 0.001;
    moved.col(0) = f.mesh.vertices.col(0).array() + offset;
    texturer.SetFrame(moved, f.cameras, f.images);
  }
}

void BM_TextureSetFrame(benchmark::State& state) {
  Fixture& f = GetFixture();
  SetFrameLoop(state, *f.texturer);
  state.counters["triangles"] = static_cast<double>(f.mesh.num_faces());
  state.counters["cameras"] = static_cast<double>(f.cameras.size());
}

void BM_TextureRender(benchmark::State& state) {
  Fixture& f = GetFixture();
  f.texturer->SetFrame(f.mesh.vertices, f.cameras, f.images);
  for (auto _ : state) {
    RenderResult result = f.texturer->Render(f.view);
    benchmark::DoNotOptimize(result.color.data.data());
  }
  state.counters["triangles"] = static_cast<double>(f.mesh.num_faces());
}

void BM_TextureFrame(benchmark::State& state) {
  Fixture& f = GetFixture();
  for (auto _ : state) {
    f.texturer->SetFrame(f.mesh.vertices, f.cameras, f.images);
    RenderResult result = f.texturer->Render(f.view);
    benchmark::DoNotOptimize(result.color.data.data());
  }
}

void BM_TextureFrame4Views(benchmark::State& state) {
  Fixture& f = GetFixture();
  const Camera views[4] = {f.view, RingCamera("novel1", 112.5, 1.2), RingCamera("novel2", 202.5, 1.8),
                           RingCamera("novel3", 292.5, 1.2)};
  for (auto _ : state) {
    f.texturer->SetFrame(f.mesh.vertices, f.cameras, f.images);
    for (const Camera& view : views) {
      RenderResult result = f.texturer->Render(view);
      benchmark::DoNotOptimize(result.color.data.data());
    }
  }
}

void BM_TextureSetFrameHalfVisibility(benchmark::State& state) {
  ProjectiveTextureOptions options;
  options.visibility_scale = 0.5;
  SetFrameLoop(state, GetFixture().Variant("half visibility", options));
}

void BM_TextureSetFrameFullMesh(benchmark::State& state) {
  ProjectiveTextureOptions options;
  options.visibility_faces = 0;
  SetFrameLoop(state, GetFixture().Variant("full mesh", options));
}

void BM_TextureFrameGlRaster(benchmark::State& state) {
  Fixture& f = GetFixture();
  ProjectiveTextureOptions options;
  options.raster = ProjectiveTextureOptions::Raster::kGl;
  ProjectiveTexturer& texturer = f.Variant("gl raster", options);
  for (auto _ : state) {
    texturer.SetFrame(f.mesh.vertices, f.cameras, f.images);
    RenderResult result = texturer.Render(f.view);
    benchmark::DoNotOptimize(result.color.data.data());
  }
}

#define CONFLUENT_TEXTURE_BENCH(name) \
  BENCHMARK(name)->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(5)->ReportAggregatesOnly(true)

CONFLUENT_TEXTURE_BENCH(BM_TextureSetFrame);
CONFLUENT_TEXTURE_BENCH(BM_TextureRender);
CONFLUENT_TEXTURE_BENCH(BM_TextureFrame);
CONFLUENT_TEXTURE_BENCH(BM_TextureFrame4Views);
CONFLUENT_TEXTURE_BENCH(BM_TextureSetFrameHalfVisibility);
CONFLUENT_TEXTURE_BENCH(BM_TextureSetFrameFullMesh);
CONFLUENT_TEXTURE_BENCH(BM_TextureFrameGlRaster);

}  // namespace
}  // namespace confluent

BENCHMARK_MAIN();
