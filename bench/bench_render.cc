// Rendering speed of MeshRenderer: a 263K-triangle mesh into a 1024x768 camera, colour and
// silhouette separately, readback included. Run with --benchmark_repetitions (default 5 here)
// and read the *_median rows: time per frame.

#include <benchmark/benchmark.h>

#include <cmath>

#include "render/renderer.h"

namespace confluent {
namespace {

// Latitude-longitude sphere: 2 * slices * (stacks - 1) triangles; 512 x 258 -> 263,168 faces.
// Radius 0.9 m at the origin; vertex colours vary so shading is not constant.
Mesh MakeBenchMesh(int slices = 512, int stacks = 258) {
  Mesh mesh;
  const int rings = stacks - 1;  // rings of vertices between the poles
  mesh.vertices.resize(2 + rings * slices, 3);
  mesh.colors.resize(mesh.vertices.rows(), 3);
  mesh.vertices.row(0) << 0, 0, 0.9;
  mesh.vertices.row(1) << 0, 0, -0.9;
  for (int r = 0; r < rings; ++r) {
    const double theta = M_PI * (r + 1) / stacks;
    for (int s = 0; s < slices; ++s) {
      const double phi = 2.0 * M_PI * s / slices;
      // Mild bumps so the surface is not a perfect sphere.
      const double radius = 0.9 * (1.0 + 0.03 * std::sin(7 * phi) * std::sin(5 * theta));
      mesh.vertices.row(2 + r * slices + s) << radius * std::sin(theta) * std::cos(phi),
          radius * std::sin(theta) * std::sin(phi), radius * std::cos(theta);
    }
  }
  for (int v = 0; v < mesh.num_vertices(); ++v)
    mesh.colors.row(v) << 0.5f + 0.4f * static_cast<float>(std::sin(10 * mesh.vertices(v, 0))), 0.4f,
        0.5f + 0.4f * static_cast<float>(std::cos(10 * mesh.vertices(v, 2)));
  std::vector<Eigen::Vector3i> faces;
  auto ring_vertex = [&](int r, int s) { return 2 + r * slices + (s % slices); };
  for (int s = 0; s < slices; ++s) {
    faces.emplace_back(0, ring_vertex(0, s), ring_vertex(0, s + 1));
    faces.emplace_back(1, ring_vertex(rings - 1, s + 1), ring_vertex(rings - 1, s));
  }
  for (int r = 0; r + 1 < rings; ++r)
    for (int s = 0; s < slices; ++s) {
      faces.emplace_back(ring_vertex(r, s), ring_vertex(r + 1, s), ring_vertex(r + 1, s + 1));
      faces.emplace_back(ring_vertex(r, s), ring_vertex(r + 1, s + 1), ring_vertex(r, s + 1));
    }
  mesh.faces.resize(faces.size(), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) mesh.faces.row(f) = faces[f].transpose();
  return mesh;
}

// A 1024x768 camera 4 m from the mesh (it covers about a quarter of the image, like an actor).
Camera BenchCamera(bool with_distortion = false) {
  Camera camera;
  camera.name = "bench";
  camera.width = 1024;
  camera.height = 768;
  camera.K << 1100.0, 0.0, 511.5, 0.0, 1100.0, 383.5, 0.0, 0.0, 1.0;
  const Eigen::Vector3d center(0.0, -4.0, 0.3), target(0.0, 0.0, 0.0);
  const Eigen::Vector3d z = (target - center).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  camera.rotation.row(0) = x.transpose();
  camera.rotation.row(1) = y.transpose();
  camera.rotation.row(2) = z.transpose();
  camera.translation = -camera.rotation * center;
  if (with_distortion) camera.dist << -0.2, 0.05, 0.0, 0.0, 0.0;
  return camera;
}

// Shared across benchmarks: one context, the mesh uploaded once.
struct Fixture {
  Mesh mesh = MakeBenchMesh();
  MeshRenderer renderer;
  int handle = renderer.AddMesh(mesh, "bench mesh");
};

// Deliberately never destroyed: tearing a GL context down from a static destructor can race
// the driver's own exit handlers.
Fixture& GetFixture() {
  static Fixture* fixture = new Fixture;
  return *fixture;
}

void RunRender(benchmark::State& state, const RenderRequest& request, bool update_vertices, bool distortion) {
  Fixture& fixture = GetFixture();
  const Camera camera = BenchCamera(distortion);
  fixture.renderer.Render(camera, request);  // warm-up (shader compile, buffers, distortion map)
  RowMatrixX3d moved = fixture.mesh.vertices;
  double offset = 0.0;
  for (auto _ : state) {
    if (update_vertices) {
      offset = offset > 0.05 ? 0.0 : offset + 0.001;
      moved.col(0) = fixture.mesh.vertices.col(0).array() + offset;
      fixture.renderer.UpdateVertices(fixture.handle, moved);
    }
    RenderResult result = fixture.renderer.Render(camera, request);
    benchmark::DoNotOptimize(result.color.data.data());
    benchmark::DoNotOptimize(result.silhouette.data.data());
  }
  state.counters["triangles"] = static_cast<double>(fixture.mesh.num_faces());
  state.SetLabel(fixture.renderer.context_info().gl_renderer);
}

RenderRequest ColorRequest() {
  RenderRequest request;
  request.color = true;
  return request;
}

RenderRequest SilhouetteRequest() {
  RenderRequest request;
  request.color = false;
  request.silhouette = true;
  return request;
}

void BM_RenderColor(benchmark::State& state) { RunRender(state, ColorRequest(), false, false); }
void BM_RenderSilhouette(benchmark::State& state) { RunRender(state, SilhouetteRequest(), false, false); }
// Per-frame animation: new vertex positions (normals recomputed) then render.
void BM_RenderColorWithVertexUpdate(benchmark::State& state) { RunRender(state, ColorRequest(), true, false); }
void BM_RenderSilhouetteWithVertexUpdate(benchmark::State& state) {
  RunRender(state, SilhouetteRequest(), true, false);
}
void BM_RenderAllOutputs(benchmark::State& state) {
  RenderRequest request;
  request.depth = request.silhouette = request.triangle_id = true;
  RunRender(state, request, false, false);
}
// Back-face culling (valid for closed meshes) skips about half of the triangle setup work.
void BM_RenderColorCulled(benchmark::State& state) {
  RenderRequest request = ColorRequest();
  request.cull_back_faces = true;
  RunRender(state, request, false, false);
}
void BM_RenderSilhouetteCulled(benchmark::State& state) {
  RenderRequest request = SilhouetteRequest();
  request.cull_back_faces = true;
  RunRender(state, request, false, false);
}
void BM_RenderColorDistorted(benchmark::State& state) { RunRender(state, ColorRequest(), false, true); }
void BM_RenderSilhouetteDistorted(benchmark::State& state) { RunRender(state, SilhouetteRequest(), false, true); }

#define CONFLUENT_RENDER_BENCH(name) \
  BENCHMARK(name)->Unit(benchmark::kMillisecond)->UseRealTime()->Repetitions(5)->ReportAggregatesOnly(true)

CONFLUENT_RENDER_BENCH(BM_RenderColor);
CONFLUENT_RENDER_BENCH(BM_RenderSilhouette);
CONFLUENT_RENDER_BENCH(BM_RenderColorWithVertexUpdate);
CONFLUENT_RENDER_BENCH(BM_RenderSilhouetteWithVertexUpdate);
CONFLUENT_RENDER_BENCH(BM_RenderAllOutputs);
CONFLUENT_RENDER_BENCH(BM_RenderColorCulled);
CONFLUENT_RENDER_BENCH(BM_RenderSilhouetteCulled);
CONFLUENT_RENDER_BENCH(BM_RenderColorDistorted);
CONFLUENT_RENDER_BENCH(BM_RenderSilhouetteDistorted);

}  // namespace
}  // namespace confluent

BENCHMARK_MAIN();
