// Real captured motion (Vlasic et al. 2008 "samba", 175 frames, shared data): the template is
// the real mesh sequence, the scan is frame 0 re-tessellated (midpoint subdivision, 4x the
// faces). Correspondences follow the augmentation rule of report section 4.2 for m of about
// 22, 60 and 180; the error is measured at the scan's original vertices against the real frames
// (the quantitative twin of the report's Figure 3). Skips when the data is absent.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include "core/mesh_io.h"
#include "core/mesh_ops.h"
#include "deform/confluent_motion.h"
#include "tests/deform/test_geometry.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

// `count` faces spread over the mesh by farthest-point sampling of face centroids, starting at
// the face with the highest y (the head; samba is Y up).
std::vector<int> FarthestFaces(const Mesh& mesh, int count) {
  const int m = mesh.num_faces();
  RowMatrixX3d centroids(m, 3);
  for (int f = 0; f < m; ++f) centroids.row(f) = testing::FaceCentroid(mesh, f).transpose();
  int current = 0;
  centroids.col(1).maxCoeff(&current);
  std::vector<double> distance(m, std::numeric_limits<double>::infinity());
  std::vector<int> result;
  for (int k = 0; k < count; ++k) {
    result.push_back(current);
    for (int f = 0; f < m; ++f)
      distance[f] = std::min(distance[f], (centroids.row(f) - centroids.row(current)).squaredNorm());
    current = static_cast<int>(std::max_element(distance.begin(), distance.end()) - distance.begin());
  }
  return result;
}

struct ErrorStats {
  std::size_t pairs = 0;
  double mean_m = 0, p95_m = 0, ms_per_frame = 0;
};

TEST(SambaRealMotion, MoreCorrespondencesReduceTheError) {
  const std::string archive = testing::SharedDataPath("meshseq/vlasic_samba.tar.xz");
  if (archive.empty()) GTEST_SKIP() << "shared data meshseq/vlasic_samba.tar.xz not available";
  testing::TempDir dir;
  const std::vector<std::string> files = testing::ExtractSambaSequence(dir.path());
  ASSERT_EQ(files.size(), 175u);
  // Every 5th frame keeps the test short; CONFLUENT_SAMBA_STRIDE=1 measures all 175.
  const char* stride_text = std::getenv("CONFLUENT_SAMBA_STRIDE");
  const int stride = stride_text ? std::max(1, std::atoi(stride_text)) : 5;
  std::vector<Mesh> frames;
  for (std::size_t i = 0; i < files.size(); i += stride) frames.push_back(ReadMesh(files[i]));
  const Mesh& reference = frames[0];
  const Mesh scan = SubdivideMidpoint(reference);  // face 4f+3 is the centre child of face f
  const int n = reference.num_vertices();

  const char* weight_text = std::getenv("CONFLUENT_SAMBA_POSITION_WEIGHT");  // for experiments
  ConfluentMotionOptions options;
  if (weight_text) options.position_weight = std::atof(weight_text);
  auto measure = [&](int seeds, int directions) {
    Correspondences pairs;
    for (int f : FarthestFaces(reference, seeds)) pairs.pairs.push_back({f, 4 * f + 3, "", 1.0});
    AugmentOptions augment;
    augment.directions = directions;
    if (directions > 1) pairs = AugmentCorrespondences(reference, scan, pairs, augment);
    ConfluentMotion motion(scan, reference, pairs, options);
    std::vector<double> errors;
    errors.reserve(frames.size() * n);
    double seconds = 0.0;
    for (const Mesh& frame : frames) {
      const auto start = std::chrono::steady_clock::now();
      const RowMatrixX3d x = motion.Deform(frame.vertices);
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      for (int v = 0; v < n; ++v) errors.push_back((x.row(v) - frame.vertices.row(v)).norm());
    }
    ErrorStats stats;
    stats.pairs = pairs.pairs.size();
    for (double e : errors) stats.mean_m += e / errors.size();
    std::nth_element(errors.begin(), errors.begin() + errors.size() * 95 / 100, errors.end());
    stats.p95_m = errors[errors.size() * 95 / 100];
    stats.ms_per_frame = 1e3 * seconds / frames.size();
    return stats;
  };
  // 22 given triangles; the augmentation rule adds rays around each part's axis: 3 directions
  // give about 60 pairs, the default 8 about 140, and 10 about 180.
  const ErrorStats few = measure(22, 1), some = measure(22, 3), standard = measure(22, 8),
                   many = measure(22, 10);
  std::printf("samba, %zu frames (stride %d), position weight %g, scan %d faces (frame 0 subdivided), error at the %d original vertices:\n",
              frames.size(), stride, options.position_weight, scan.num_faces(), n);
  std::printf("| pairs | mean error (cm) | 95th percentile (cm) | ms per frame |\n|---|---|---|---|\n");
  for (const ErrorStats* s : {&few, &some, &standard, &many})
    std::printf("| %zu | %.2f | %.2f | %.1f |\n", s->pairs, 100 * s->mean_m, 100 * s->p95_m, s->ms_per_frame);
  EXPECT_GE(some.pairs, 50u);
  EXPECT_GE(standard.pairs, 140u);
  EXPECT_GE(many.pairs, 170u);
  EXPECT_LT(some.mean_m, few.mean_m);
  EXPECT_LT(many.mean_m, some.mean_m);
  EXPECT_LT(many.mean_m, 0.8 * few.mean_m);
  EXPECT_LE(many.mean_m, 0.02);
}

}  // namespace
}  // namespace confluent
