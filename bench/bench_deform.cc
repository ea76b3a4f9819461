// Confluent Motion speed (deform/confluent_motion.h) on elongated sphere "scans" of about 12K,
// 50K, 132K and 264K triangles, driven by a 16-segment rigid template (a chain of 16 slabs,
// about 12 labelled correspondences each: ~190 pairs).
//   BM_Factor:        construction (both Cholesky factorisations + 16 weight fields)
//   BM_FrameSegments: one frame, segment-rigid fast path (weight fields)
//   BM_FrameGeneral:  one frame, the same pairs without labels (harmonic solve per frame)
//   BM_FrameSegmentsSingle: BM_FrameSegments with single-precision factors (an option)
// Report per-frame medians; the scaling exponent is the slope of log(time) over log(triangles).

#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <map>
#include <memory>

#include "core/mesh_ops.h"
#include "deform/confluent_motion.h"

namespace confluent {
namespace {

constexpr int kSegments = 16;
constexpr double kHeight = 1.6;

Mesh Elongated(int rings, int segments) {
  Mesh mesh = MakeUvSphere(0.2, rings, segments);
  mesh.vertices.col(2) *= kHeight / 0.4;  // z in [-0.8, 0.8]
  return mesh;
}

int SlabOf(double z) { return std::clamp(static_cast<int>((z + kHeight / 2) / (kHeight / kSegments)), 0, kSegments - 1); }

Eigen::Vector3d Centroid(const Mesh& mesh, int f) {
  return (mesh.vertices.row(mesh.faces(f, 0)) + mesh.vertices.row(mesh.faces(f, 1)) + mesh.vertices.row(mesh.faces(f, 2)))
             .transpose() / 3.0;
}

// The template posed at `frame`: slab s rotated by a chain of rotations about x at the slab joints.
RowMatrixX3d Pose(const Mesh& template_mesh, int frame) {
  std::vector<Eigen::Isometry3d> transforms(kSegments);
  Eigen::Isometry3d chain = Eigen::Isometry3d::Identity();
  for (int s = 0; s < kSegments; ++s) {
    const Eigen::Vector3d joint(0, 0, -kHeight / 2 + s * kHeight / kSegments);
    const double angle = 0.15 * std::sin(0.3 * frame + s);
    chain = chain * Eigen::Translation3d(joint) * Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()) *
            Eigen::Translation3d(-joint);
    transforms[s] = chain;
  }
  RowMatrixX3d posed(template_mesh.num_vertices(), 3);
  for (int v = 0; v < template_mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = template_mesh.vertices.row(v);
    posed.row(v) = (transforms[SlabOf(p.z())] * p).transpose();
  }
  return posed;
}

struct Scene {
  Mesh scan, template_mesh;
  Correspondences labelled, unlabelled;
  explicit Scene(int triangles) {
    const int rings = static_cast<int>(std::lround(std::sqrt(triangles / 4.0)));
    scan = Elongated(rings, 2 * rings);
    template_mesh = Elongated(40, 48);
    // ~12 pairs per slab: template faces entirely inside the slab, spread around.
    std::map<int, int> per_slab;
    for (int f = 0; f < template_mesh.num_faces(); f += 7) {
      const int s = SlabOf(template_mesh.vertices(template_mesh.faces(f, 0), 2));
      bool inside = true;
      for (int k = 1; k < 3; ++k) inside = inside && SlabOf(template_mesh.vertices(template_mesh.faces(f, k), 2)) == s;
      if (!inside || per_slab[s] >= 12) continue;
      const Eigen::Vector3d c = Centroid(template_mesh, f);
      int best = -1;
      double best_d = std::numeric_limits<double>::infinity();
      for (int g = 0; g < scan.num_faces(); ++g) {
        const double d = (Centroid(scan, g) - c).squaredNorm();
        if (d < best_d) best_d = d, best = g;
      }
      bool used = false;
      for (const auto& pair : labelled.pairs) used = used || pair.scan_triangle == best;
      if (used) continue;
      ++per_slab[s];
      labelled.pairs.push_back({f, best, "slab" + std::to_string(s), 1.0});
      unlabelled.pairs.push_back({f, best, "", 1.0});
    }
  }
};

const Scene& GetScene(int triangles) {
  static std::map<int, std::unique_ptr<Scene>> scenes;
  auto& scene = scenes[triangles];
  if (!scene) scene = std::make_unique<Scene>(triangles);
  return *scene;
}

void SetCounters(benchmark::State& state, const Scene& scene) {
  state.counters["triangles"] = scene.scan.num_faces();
  state.counters["pairs"] = static_cast<double>(scene.labelled.pairs.size());
}

void BM_Factor(benchmark::State& state) {
  const Scene& scene = GetScene(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    ConfluentMotion motion(scene.scan, scene.template_mesh, scene.labelled);
    benchmark::DoNotOptimize(motion.setup_summary().poisson_factor_nonzeros);
  }
  SetCounters(state, scene);
}

void RunFrames(benchmark::State& state, bool labelled, bool single_precision = false) {
  const Scene& scene = GetScene(static_cast<int>(state.range(0)));
  ConfluentMotionOptions options;
  options.single_precision_solves = single_precision;
  ConfluentMotion motion(scene.scan, scene.template_mesh, labelled ? scene.labelled : scene.unlabelled, options);
  std::vector<RowMatrixX3d> poses;
  for (int f = 0; f < 8; ++f) poses.push_back(Pose(scene.template_mesh, f));
  int frame = 0;
  DeformSummary summary;
  for (auto _ : state) {
    const RowMatrixX3d x = motion.Deform(poses[frame++ % poses.size()], &summary);
    benchmark::DoNotOptimize(x.data());
  }
  if (summary.used_segment_fields != labelled) state.SkipWithError("unexpected path");
  SetCounters(state, scene);
  state.counters["factor_s"] = motion.setup_summary().factor_seconds;
  state.counters["poisson_nnz"] = motion.setup_summary().poisson_factor_nonzeros;
}

void BM_FrameSegments(benchmark::State& state) { RunFrames(state, true); }
void BM_FrameGeneral(benchmark::State& state) { RunFrames(state, false); }
void BM_FrameSegmentsSingle(benchmark::State& state) { RunFrames(state, true, true); }

BENCHMARK(BM_Factor)->Arg(12500)->Arg(50000)->Arg(132000)->Arg(264000)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(BM_FrameSegments)->Arg(12500)->Arg(50000)->Arg(132000)->Arg(264000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FrameGeneral)->Arg(12500)->Arg(50000)->Arg(132000)->Arg(264000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FrameSegmentsSingle)->Arg(50000)->Arg(264000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace confluent

BENCHMARK_MAIN();
