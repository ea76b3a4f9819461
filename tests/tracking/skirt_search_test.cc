// The skirt chosen by overlap on a grid (tracking/skirt_search.h): the global best of two optima,
// a short flared skirt recovered from its own masks from the long tube the fit settles on, the
// fitted skirt kept without a clear gain, and bad input refused.

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "calib/rig_check.h"
#include "core/error.h"
#include "silhouette/overlap.h"
#include "tests/support/camera_ring.h"
#include "tracking/skirt_search.h"

namespace confluent {
namespace {

BodyShape Skirted(double length_m, double flare_m) {
  BodyShape shape = BodyShape::Uniform(1.65);
  shape.skirt_length_m = length_m;
  shape.skirt_flare_m = flare_m;
  return shape;
}

// Two optima, shaped like samba's first frame's (a grid over its overlap): a long straight tube
// (0.60 m, no flare: 0.856), where the fit ends, and a short flared skirt (0.35 m, 0.08 m:
// 0.882), with lower ground between them (0.831 at 0.47 m, 0.04 m).
double TwoOptima(const BodyShape& shape) {
  const auto bump = [&](double length, double flare, double height, double length_width, double flare_width) {
    const double dl = (shape.skirt_length_m - length) / length_width, df = (shape.skirt_flare_m - flare) / flare_width;
    return height * std::exp(-(dl * dl + df * df));
  };
  return 0.8 + std::max(bump(0.60, 0.0, 0.056, 0.3, 0.05), bump(0.35, 0.08, 0.082, 0.17, 0.058));
}

TEST(SkirtSearch, FindsTheBestOfTwoOptimaFromTheWorse) {
  const BodyShape tube = Skirted(0.60, 0.0);
  const SkirtSearchResult found = SearchSkirt(tube, SkirtSearchOptions(), TwoOptima);
  EXPECT_TRUE(found.changed);
  // Within half the last refinement's steps (0.025 m of length, 0.01 m of flare).
  EXPECT_NEAR(found.shape.skirt_length_m, 0.35, 0.0125 + 1e-9);
  EXPECT_NEAR(found.shape.skirt_flare_m, 0.08, 0.005 + 1e-9);
  EXPECT_GT(found.overlap, 0.88);
  EXPECT_DOUBLE_EQ(found.overlap, TwoOptima(found.shape));
  // Only the skirt changes.
  EXPECT_EQ(found.shape.girth_scale, tube.girth_scale);
  EXPECT_EQ(found.shape.length_scale, tube.length_scale);
  // The coarse grid (8 lengths x 8 flares for this body) and two refinements of 8 each, at most.
  EXPECT_LE(found.evaluations, 1 + 64 + 16);
}

// Real geometry: masks of a template wearing a short flared skirt, searched from the long tube.
TEST(SkirtSearch, RecoversAShortFlaredSkirtFromItsMasks) {
  const BodyTemplate body;
  const Rig rig = testing::CameraRing(8, 160, 120, 0.3, 1.4, 0.5, Eigen::Vector3d(0, 0, 0.9));
  TemplatePose pose;
  pose.root_rotation = Eigen::Vector3d(0, 0, 0.4);
  pose.dofs[kJointLeftShoulder] = {0.2, 0.5, 0.0};
  pose.dofs[kJointRightShoulder] = {-0.1, -0.4, 0.0};
  const BodyShape truth = Skirted(0.35, 0.10);
  std::vector<Image> masks;
  for (const Camera& camera : rig.cameras) masks.push_back(RasterizeClosedMesh(body.PosedMesh(truth, pose), camera));
  const auto overlap = [&](const BodyShape& shape) {
    const Mesh mesh = body.PosedMesh(shape, pose);
    double sum = 0.0;
    for (std::size_t c = 0; c < rig.cameras.size(); ++c) sum += MaskIoU(RasterizeClosedMesh(mesh, rig.cameras[c]), masks[c]);
    return sum / rig.cameras.size();
  };
  const BodyShape tube = Skirted(0.60, 0.0);
  const SkirtSearchResult found = SearchSkirt(tube, SkirtSearchOptions(), overlap);
  ASSERT_TRUE(found.changed);
  EXPECT_NEAR(found.shape.skirt_length_m, truth.skirt_length_m, 0.05);
  EXPECT_NEAR(found.shape.skirt_flare_m, truth.skirt_flare_m, 0.02);
  EXPECT_GT(found.overlap, overlap(tube) + 0.02);
  EXPECT_GT(found.overlap, 0.97);
}

TEST(SkirtSearch, KeepsTheFittedSkirtWithoutTheMinimumGain) {
  const BodyShape fitted = Skirted(0.5, 0.05);
  // Every other skirt overlaps at most 0.0003 better, under the 0.003 asked.
  const auto nearly_flat = [](const BodyShape& shape) { return 0.9 + 0.001 * shape.skirt_flare_m; };
  const SkirtSearchResult found = SearchSkirt(fitted, SkirtSearchOptions(), nearly_flat);
  EXPECT_FALSE(found.changed);
  EXPECT_EQ(found.shape.skirt_length_m, fitted.skirt_length_m);
  EXPECT_EQ(found.shape.skirt_flare_m, fitted.skirt_flare_m);
  EXPECT_DOUBLE_EQ(found.overlap, nearly_flat(fitted));
  // With no minimum gain the better skirt is taken.
  SkirtSearchOptions options;
  options.min_gain = 0.0;
  EXPECT_TRUE(SearchSkirt(fitted, options, nearly_flat).changed);
}

TEST(SkirtSearch, ShapeWithoutSkirtAndBadOptionsAreRefused) {
  const auto constant = [](const BodyShape&) { return 0.5; };
  EXPECT_THROW(SearchSkirt(BodyShape::Uniform(1.7), SkirtSearchOptions(), constant), std::invalid_argument);
  SkirtSearchOptions options;
  options.flare_step_m = -0.01;
  EXPECT_THROW(SearchSkirt(BodyShape::Uniform(1.7), options, constant), UsageError);
}

}  // namespace
}  // namespace confluent
