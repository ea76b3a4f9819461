// The deform stage's refinement frame after frame (pipeline/frame_refinement.h): a sphere that
// moves, deformed every frame with the same error (7% too small), refined against the true
// sphere's silhouettes in 6 ring cameras.

#include "pipeline/frame_refinement.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/mesh_ops.h"
#include "silhouette/overlap.h"

namespace confluent {
namespace {

constexpr double kRadius = 0.3;

Eigen::RowVector3d Centre(int frame) { return Eigen::RowVector3d(0.01 * frame, -0.004 * frame, 0.0); }

struct MovingSphere {
  Mesh shape = MakeUvSphere(kRadius, 40, 80);
  std::vector<Camera> cameras;
  MovingSphere() {
    for (int k = 0; k < 6; ++k) {
      const double azimuth = 2.0 * M_PI * k / 6;
      const Eigen::Vector3d centre(3.0 * std::cos(azimuth), 3.0 * std::sin(azimuth), k % 2 ? 0.8 : -0.4);
      cameras.push_back(LookAtCamera("ring" + std::to_string(k), centre, Eigen::Vector3d::Zero(), 320, 240, 320.0));
    }
  }
  std::vector<Image> Masks(int frame) const {
    Mesh truth = shape;
    truth.vertices = shape.vertices.rowwise() + Centre(frame);
    std::vector<Image> masks;
    for (const Camera& camera : cameras) masks.push_back(RasterizeClosedMesh(truth, camera));
    return masks;
  }
  RowMatrixX3d Deformed(int frame) const { return (0.93 * shape.vertices).rowwise() + Centre(frame); }
  double Error(int frame, const RowMatrixX3d& vertices) const {
    return ((vertices.rowwise() - Centre(frame)).rowwise().norm().array() - kRadius).abs().mean();
  }
};

double Mean(const std::vector<double>& values) {
  double sum = 0.0;
  for (double value : values) sum += value;
  return sum / values.size();
}

FrameRefinementOptions SilhouettesOnly(int keyframe_interval) {
  FrameRefinementOptions options;
  options.photo = false;
  options.keyframe_interval = keyframe_interval;
  return options;
}

TEST(FrameRefinement, AFrameAfterItsPredecessorStartsFromTheCarriedCorrection) {
  const MovingSphere sphere;
  FrameRefinement refinement(sphere.shape, sphere.cameras, SilhouettesOnly(10));
  FrameRefinementSummary first, second;
  const RowMatrixX3d refined0 = refinement.Refine(0, sphere.Deformed(0), sphere.Masks(0), {}, &first);
  const RowMatrixX3d refined1 = refinement.Refine(1, sphere.Deformed(1), sphere.Masks(1), {}, &second);
  EXPECT_FALSE(first.carried);
  EXPECT_TRUE(second.carried);
  // The carried start is nearly where frame 0 ended, far above the deformation's overlap.
  EXPECT_LT(Mean(first.iou_start), 0.93);
  EXPECT_GT(Mean(second.iou_start), Mean(first.iou_after) - 0.01);
  // With its fewer rounds, frame 1 ends at least as close to the true sphere as frame 0.
  EXPECT_LT(sphere.Error(0, refined0), 0.25 * sphere.Error(0, sphere.Deformed(0)));
  EXPECT_LE(sphere.Error(1, refined1), sphere.Error(0, refined0) * 1.05);
  EXPECT_GT(Mean(second.iou_after), 0.98);
}

TEST(FrameRefinement, KeyframesAndFramesWithoutTheirPredecessorStartFromTheDeformation) {
  const MovingSphere sphere;
  FrameRefinement every_frame(sphere.shape, sphere.cameras, SilhouettesOnly(1));
  FrameRefinement in_tens(sphere.shape, sphere.cameras, SilhouettesOnly(10));
  FrameRefinementSummary summary, cold;
  every_frame.Refine(0, sphere.Deformed(0), sphere.Masks(0), {});
  every_frame.Refine(1, sphere.Deformed(1), sphere.Masks(1), {}, &summary);
  EXPECT_FALSE(summary.carried);
  in_tens.Refine(1, sphere.Deformed(1), sphere.Masks(1), {}, &cold);  // frame 0 was not refined here
  EXPECT_FALSE(cold.carried);
  EXPECT_EQ(cold.iou_start, summary.iou_start);
  in_tens.Refine(9, sphere.Deformed(9), sphere.Masks(9), {});
  in_tens.Refine(10, sphere.Deformed(10), sphere.Masks(10), {}, &summary);
  EXPECT_FALSE(summary.carried);
  EXPECT_TRUE(in_tens.IsKeyframe(20));
  EXPECT_FALSE(in_tens.IsKeyframe(21));
}

TEST(FrameRefinement, ReplayingFromTheKeyframeGivesTheSameFrame) {
  const MovingSphere sphere;
  FrameRefinement uninterrupted(sphere.shape, sphere.cameras, SilhouettesOnly(10));
  RowMatrixX3d last;
  for (int frame = 10; frame <= 12; ++frame) last = uninterrupted.Refine(frame, sphere.Deformed(frame), sphere.Masks(frame), {});
  FrameRefinement resumed(sphere.shape, sphere.cameras, SilhouettesOnly(10));
  for (int frame = 10; frame < 12; ++frame) resumed.Refine(frame, sphere.Deformed(frame), sphere.Masks(frame), {});
  EXPECT_EQ(resumed.Refine(12, sphere.Deformed(12), sphere.Masks(12), {}), last);
}

TEST(FrameRefinement, TheCarriedCorrectionTurnsWithTheSurface) {
  const MovingSphere sphere;
  FrameRefinementOptions options = SilhouettesOnly(10);
  options.carried_silhouette_rounds = 0;  // frame 1 is its deformation plus the carried correction
  FrameRefinement refinement(sphere.shape, sphere.cameras, options);
  // Frame 1 is frame 0's deformation turned by 40 degrees about a tilted axis through a point off
  // the centre: frame 0's correction, turned alike, must come back.
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -0.5, 1.0).normalized()).toRotationMatrix();
  const Eigen::RowVector3d pivot(0.05, 0.1, -0.2);
  auto turned = [&](const RowMatrixX3d& vertices) -> RowMatrixX3d {
    return ((vertices.rowwise() - pivot) * turn.transpose()).rowwise() + pivot;
  };
  const RowMatrixX3d refined0 = refinement.Refine(0, sphere.Deformed(0), sphere.Masks(0), {});
  ASSERT_GT((refined0 - sphere.Deformed(0)).rowwise().norm().maxCoeff(), 0.01);  // a correction worth carrying
  FrameRefinementSummary summary;
  const RowMatrixX3d refined1 = refinement.Refine(1, turned(sphere.Deformed(0)), sphere.Masks(0), {}, &summary);
  EXPECT_TRUE(summary.carried);
  EXPECT_LT((refined1 - turned(refined0)).rowwise().norm().maxCoeff(), 1e-9);
}

TEST(FrameRefinement, InvalidOptionsAreNamed) {
  const MovingSphere sphere;
  FrameRefinementOptions options;
  options.keyframe_interval = 0;
  try {
    FrameRefinement refinement(sphere.shape, sphere.cameras, options);
    FAIL() << "accepted keyframe_interval 0";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("keyframe_interval"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace confluent
