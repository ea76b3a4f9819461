// Silhouette refinement (refine/silhouette_refinement.h): a sphere that is too small and off
// centre is pulled onto the silhouettes of the true sphere, seen by a ring of cameras.

#include <gtest/gtest.h>

#include <cmath>

#include "calib/rig_check.h"
#include "core/mesh_ops.h"
#include "refine/silhouette_refinement.h"
#include "silhouette/overlap.h"

namespace confluent {
namespace {

// A 320x240 camera on a ring of radius 3 m at height `height_m`, looking at the origin.
Camera RingCamera(double azimuth_rad, double height_m) {
  const Eigen::Vector3d centre(3.0 * std::cos(azimuth_rad), 3.0 * std::sin(azimuth_rad), height_m);
  return LookAtCamera("ring", centre, Eigen::Vector3d::Zero(), 320, 240, 320.0);
}

// Mean distance of the vertices from the true sphere (radius 0.3 m at the origin).
double SphereError(const RowMatrixX3d& vertices) {
  return (vertices.rowwise().norm().array() - 0.3).abs().mean();
}

// The true sphere (radius 0.3 m at the origin) seen by 6 ring cameras, alternately low and
// high, and a start that is too small and off centre.
struct OffsetSphere {
  Mesh truth = MakeUvSphere(0.3, 48, 96);
  std::vector<Camera> cameras;
  std::vector<Image> masks;
  Mesh start;
  OffsetSphere() {
    for (int k = 0; k < 6; ++k) {
      cameras.push_back(RingCamera(2.0 * M_PI * k / 6, k % 2 ? 0.8 : -0.4));
      masks.push_back(RasterizeClosedMesh(truth, cameras.back()));
    }
    start = truth;
    start.vertices = (0.93 * truth.vertices).rowwise() + Eigen::RowVector3d(0.03, -0.02, 0.01);
  }
};

TEST(SilhouetteRefinement, PullsAnOffsetShrunkSphereOntoTheSilhouettes) {
  const OffsetSphere sphere;
  const Mesh& truth = sphere.truth;
  const std::vector<Camera>& cameras = sphere.cameras;
  const std::vector<Image>& masks = sphere.masks;
  const Mesh& start = sphere.start;
  SilhouetteRefiner refiner(start);
  SilhouetteRefinementSummary summary;
  const RowMatrixX3d refined = refiner.Refine(start.vertices, cameras, masks, &summary);
  ASSERT_TRUE(refined.allFinite());
  ASSERT_EQ(summary.iou_before.size(), cameras.size());
  for (std::size_t c = 0; c < cameras.size(); ++c) {
    EXPECT_GT(summary.iou_after[c], 0.98) << c;
    EXPECT_GT(summary.iou_after[c], summary.iou_before[c] + 0.05) << c;
  }
  EXPECT_GT(summary.rim_vertices, 100);
  EXPECT_LT(SphereError(refined), 0.2 * SphereError(start.vertices));
  // A camera the refinement never saw agrees better too.
  const Camera unseen = RingCamera(0.5, 1.6);
  const Image unseen_mask = RasterizeClosedMesh(truth, unseen);
  Mesh refined_mesh = start;
  refined_mesh.vertices = refined;
  EXPECT_GT(MaskIoU(RasterizeClosedMesh(refined_mesh, unseen), unseen_mask),
            MaskIoU(RasterizeClosedMesh(start, unseen), unseen_mask) + 0.05);
}

// Far too large a step overshoots; the line search takes such rounds back at half the gain, so
// the refinement still converges and never ends below where it started.
TEST(SilhouetteRefinement, OvershootingStepsAreTakenBack) {
  const OffsetSphere sphere;
  const std::vector<Camera>& cameras = sphere.cameras;
  const std::vector<Image>& masks = sphere.masks;
  const Mesh& start = sphere.start;
  RowMatrixX3d refined;
  auto mean_iou_after = [&](double gain, int iterations) {
    SilhouetteRefinementOptions options;
    options.step_gain = gain;
    options.iterations = iterations;
    SilhouetteRefinementSummary summary;
    refined = SilhouetteRefiner(start, options).Refine(start.vertices, cameras, masks, &summary);
    double sum = 0.0;
    for (double iou : summary.iou_after) sum += iou;
    return sum / summary.iou_after.size();
  };
  // One round at gain 6 overshoots: it is taken back, so the result is the start itself.
  double before = 0.0;
  for (std::size_t c = 0; c < cameras.size(); ++c) before += MaskIoU(RasterizeClosedMesh(start, cameras[c]), masks[c]);
  before /= cameras.size();
  EXPECT_NEAR(mean_iou_after(6.0, 1), before, 1e-12);
  EXPECT_EQ(refined, start.vertices);
  // With rounds to spare, the halved gain gets there.
  EXPECT_GT(mean_iou_after(6.0, 12), 0.98);
}

// A per-call round count overrides the options': 0 rounds leave the vertices as they are, and
// 3 rounds equal a refiner built with 3.
TEST(SilhouetteRefinement, RoundsCanBeSetPerCall) {
  const OffsetSphere sphere;
  SilhouetteRefiner refiner(sphere.start);
  SilhouetteRefinementSummary summary;
  EXPECT_EQ(refiner.Refine(sphere.start.vertices, sphere.cameras, sphere.masks, &summary, 0), sphere.start.vertices);
  for (std::size_t c = 0; c < sphere.cameras.size(); ++c) EXPECT_EQ(summary.iou_after[c], summary.iou_before[c]) << c;
  SilhouetteRefinementOptions three;
  three.iterations = 3;
  const RowMatrixX3d expected = SilhouetteRefiner(sphere.start, three).Refine(sphere.start.vertices, sphere.cameras, sphere.masks);
  const RowMatrixX3d refined = refiner.Refine(sphere.start.vertices, sphere.cameras, sphere.masks, nullptr, 3);
  EXPECT_LT((refined - expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT((refined - sphere.start.vertices).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(RasterizeClosedMesh, SphereCoversItsProjectedDisc) {
  const Mesh sphere = MakeUvSphere(0.3, 64, 128);
  const Camera camera = RingCamera(0.3, 0.0);  // the sphere's centre projects to the principal point
  const Image mask = RasterizeClosedMesh(sphere, camera);
  long covered = 0;
  for (std::uint8_t v : mask.data) covered += v == 255;
  // The outline of a sphere at distance d seen with focal f is a circle of radius f r / sqrt(d^2 - r^2).
  const double radius_px = 320.0 * 0.3 / std::sqrt(9.0 - 0.09);
  EXPECT_NEAR(covered, M_PI * radius_px * radius_px, 0.02 * M_PI * radius_px * radius_px);
  // The centre-sampled fill lies within the conservative one.
  const Image conservative = RasterizeSilhouette(sphere, camera);
  for (std::size_t i = 0; i < mask.data.size(); ++i)
    if (mask.data[i]) {
      ASSERT_EQ(conservative.data[i], 255) << i;
    }
}

TEST(SilhouetteRefinement, EmptyMasksAreSkippedAndWrongSizesRefused) {
  const Mesh sphere = MakeUvSphere(0.3, 16, 32);
  SilhouetteRefiner refiner(sphere);
  const std::vector<Camera> cameras = {RingCamera(0.0, 0.0)};
  SilhouetteRefinementSummary summary;
  const RowMatrixX3d same = refiner.Refine(sphere.vertices, cameras, {Image(320, 240, 1)}, &summary);
  EXPECT_EQ(same, sphere.vertices);
  EXPECT_TRUE(std::isnan(summary.iou_before[0]));
  EXPECT_THROW(refiner.Refine(sphere.vertices, cameras, {Image(100, 100, 1)}), std::invalid_argument);
}

}  // namespace
}  // namespace confluent
