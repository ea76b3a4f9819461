// Mesh I/O speed on a ~264K-triangle sphere (UV sphere subdivided twice), with vertex colours.
// Files go to the system temp folder and are removed at exit.

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "core/mesh_io.h"
#include "core/mesh_ops.h"
#include "core/mesh_validation.h"

namespace confluent {
namespace {

namespace fs = std::filesystem;

// The benchmark mesh (264,000 faces, 132,002 vertices) and a scratch folder for its files.
struct Scene {
  Mesh mesh;
  fs::path folder;
  Scene() {
    mesh = SubdivideMidpoint(SubdivideMidpoint(MakeUvSphere(1.0, 56, 150)));
    mesh.colors.resize(mesh.num_vertices(), 3);
    for (int v = 0; v < mesh.num_vertices(); ++v)
      mesh.colors.row(v) = (0.5 * (mesh.vertices.row(v).array() + 1.0)).cast<float>();
    folder = fs::temp_directory_path() / ("confluent_bench_mesh_io_" + std::to_string(getpid()));
    fs::create_directories(folder);
  }
  ~Scene() {
    std::error_code ignored;
    fs::remove_all(folder, ignored);
  }
  std::string Path(const std::string& name) const { return (folder / name).string(); }
};

const Scene& GetScene() {
  static const Scene scene;
  return scene;
}

void SetCounters(benchmark::State& state, const Mesh& mesh) {
  state.counters["faces"] = mesh.num_faces();
  state.SetItemsProcessed(state.iterations() * mesh.num_faces());
}

void BM_WriteMesh(benchmark::State& state, const std::string& name, bool binary) {
  const Scene& scene = GetScene();
  MeshWriteOptions options;
  options.binary = binary;
  for (auto _ : state) WriteMesh(scene.Path(name), scene.mesh, options);
  SetCounters(state, scene.mesh);
  state.counters["MB"] = static_cast<double>(fs::file_size(scene.Path(name))) / 1e6;
}

void BM_ReadMesh(benchmark::State& state, const std::string& name, bool binary) {
  const Scene& scene = GetScene();
  MeshWriteOptions options;
  options.binary = binary;
  WriteMesh(scene.Path(name), scene.mesh, options);
  for (auto _ : state) {
    Mesh mesh = ReadMesh(scene.Path(name));
    benchmark::DoNotOptimize(mesh.vertices.data());
  }
  SetCounters(state, scene.mesh);
}

void BM_ValidateMesh(benchmark::State& state) {
  const Scene& scene = GetScene();
  for (auto _ : state) {
    MeshReport report = ValidateMesh(scene.mesh);
    benchmark::DoNotOptimize(report.num_components);
  }
  SetCounters(state, scene.mesh);
}

BENCHMARK_CAPTURE(BM_WriteMesh, ply_binary, "mesh.ply", true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadMesh, ply_binary, "mesh.ply", true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WriteMesh, ply_ascii, "mesh_ascii.ply", false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadMesh, ply_ascii, "mesh_ascii.ply", false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WriteMesh, obj, "mesh.obj", false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ReadMesh, obj, "mesh.obj", false)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ValidateMesh)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace confluent

BENCHMARK_MAIN();
