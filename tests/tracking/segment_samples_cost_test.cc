// SegmentSamplesCost's hand-written Jacobian against Ceres' numeric differentiation
// (GradientChecker), and its residuals against the camera's own projection of the posed samples
// into a distance field of known form.

#include "tracking/segment_samples_cost.h"

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <cmath>

#include "tests/support/camera_ring.h"
#include "tracking/body_model_impl.h"
#include "tracking/fit_params.h"

namespace confluent {
namespace {

namespace ti = tracking_internal;

// A distance field in reduced pixels: the distance to `centre` plus `offset` (everywhere
// positive when `offset` > 0, everywhere negative when `offset` is below minus the diagonal).
struct DistanceField {
  int rows, cols;
  std::vector<float> values;
  std::unique_ptr<ceres::Grid2D<float, 1>> grid;
  std::unique_ptr<ti::SignedDistanceInterpolator> interpolator;
  DistanceField(int rows_, int cols_, Eigen::Vector2d centre, double offset) : rows(rows_), cols(cols_) {
    for (int y = 0; y < rows; ++y)
      for (int x = 0; x < cols; ++x) values.push_back(float((Eigen::Vector2d(x, y) - centre).norm() + offset));
    grid = std::make_unique<ceres::Grid2D<float, 1>>(values.data(), 0, rows, 0, cols);
    interpolator = std::make_unique<ti::SignedDistanceInterpolator>(*grid);
  }
};

struct PosedHand {
  BodyTemplate body;
  int segment = int(BodySegment::kRightHand);
  int joint = body.segments()[segment].joint;
  std::vector<int> chain = ti::SegmentChains(body)[segment];
  std::array<Eigen::Vector3d, kNumTemplateJoints> rest;
  std::vector<Eigen::Vector3d> local_samples;
  Eigen::Matrix3d root_reference;
  Camera camera = testing::CameraRing(1, 320, 240).cameras[0];
  double scale = 4.0;  // 80 x 60 reduced pixels
  // Parameter values: root translation, root rotation, then the chain's DOFs.
  std::vector<std::vector<double>> values;

  PosedHand() {
    double length[kNumBodySegments], girth[kNumBodySegments];
    std::fill(length, length + kNumBodySegments, 1.0);
    std::fill(girth, girth + kNumBodySegments, 1.0);
    ti::RestPositions(body, length, girth, &rest);
    const ti::SegmentFrame<double> frame = ti::MakeSegmentFrame(body, segment, rest, length, girth);
    for (const SurfaceCoord& sc : body.sample_coords()) local_samples.push_back(frame.Point(sc) - rest[joint]);
    const double reference_aa[3] = {0.1, -0.2, 0.3};
    root_reference = ti::AngleAxisMatrix(reference_aa);
    values.push_back({0.03, -0.02, 0.05});
    values.push_back({0.02, 0.01, -0.03});
    double angle = 0.1;
    for (int j : chain) {
      std::vector<double> dofs;
      for (int k = 0; k < body.dofs()[j].num_dof(); ++k, angle += 0.07) dofs.push_back(angle * (k % 2 ? -1 : 1));
      values.push_back(dofs);
    }
  }
  std::vector<const double*> Parameters() const {
    std::vector<const double*> pointers;
    for (const auto& v : values) pointers.push_back(v.data());
    return pointers;
  }
  ti::SegmentSamplesCost Cost(const DistanceField& field) const {
    return ti::SegmentSamplesCost(body, joint, chain, root_reference, rest, local_samples, camera, scale,
                                  *field.interpolator);
  }
  // The samples in the world, posed by the parameters.
  std::vector<Eigen::Vector3d> WorldSamples() const {
    const double* joint_params[kNumTemplateJoints] = {};
    for (std::size_t i = 0; i < chain.size(); ++i) joint_params[chain[i]] = values[2 + i].data();
    Eigen::Matrix3d R;
    Eigen::Vector3d P;
    ti::JointWorldTransform(body, joint, rest, values[0].data(), values[1].data(), root_reference, joint_params, &R, &P);
    std::vector<Eigen::Vector3d> world;
    for (const Eigen::Vector3d& local : local_samples) world.push_back(R * local + P);
    return world;
  }
};

void ExpectJacobianMatchesNumeric(const PosedHand& setup, const DistanceField& field) {
  const ti::SegmentSamplesCost cost = setup.Cost(field);
  // Small first steps: the field is a cubic spline over reduced pixels, smooth within a cell only.
  ceres::NumericDiffOptions numeric;
  numeric.ridders_relative_initial_step_size = 1e-5;
  const ceres::GradientChecker checker(&cost, static_cast<const std::vector<const ceres::Manifold*>*>(nullptr), numeric);
  ceres::GradientChecker::ProbeResults results;
  const std::vector<const double*> parameters = setup.Parameters();
  checker.Probe(parameters.data(), 1e-6, &results);
  // Entry by entry, relative to the block's largest (entries that are zero but for rounding,
  // 1e-11, make Probe's own relative test fail).
  ASSERT_EQ(results.jacobians.size(), setup.values.size());
  for (std::size_t b = 0; b < results.jacobians.size(); ++b) {
    const Eigen::MatrixXd& analytic = results.jacobians[b];
    const Eigen::MatrixXd& numeric = results.numeric_jacobians[b];
    const double largest = std::max(numeric.cwiseAbs().maxCoeff(), 1e-3);
    EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-6 * largest) << "block " << b << "\n" << results.error_log;
    EXPECT_GT(largest, 1e-3) << "block " << b << " does not move the samples";
  }
  // The residuals: the field where the camera projects each posed sample.
  std::vector<double> residuals(setup.local_samples.size());
  ASSERT_TRUE(cost.Evaluate(parameters.data(), residuals.data(), nullptr));
  const std::vector<Eigen::Vector3d> world = setup.WorldSamples();
  for (std::size_t i = 0; i < world.size(); ++i) {
    const Eigen::Vector2d px = setup.camera.Project(world[i]);
    double sd;
    field.interpolator->Evaluate((px.y() + 0.5) / setup.scale - 0.5, (px.x() + 0.5) / setup.scale - 0.5, &sd);
    EXPECT_NEAR(residuals[i], std::max(sd, 0.0), 1e-9) << "sample " << i;
  }
}

TEST(SegmentSamplesCost, JacobianMatchesNumericDifferentiationOutsideTheSilhouette) {
  const PosedHand setup;
  const DistanceField field(60, 80, Eigen::Vector2d(20, 45), 3.0);
  ExpectJacobianMatchesNumeric(setup, field);
  // The field is positive everywhere: every sample has a residual that moves with the pose.
  std::vector<double> residuals(setup.local_samples.size());
  ASSERT_TRUE(setup.Cost(field).Evaluate(setup.Parameters().data(), residuals.data(), nullptr));
  for (double r : residuals) EXPECT_GT(r, 3.0);
}

TEST(SegmentSamplesCost, JacobianMatchesNumericDifferentiationThroughLensDistortion) {
  PosedHand setup;
  setup.camera.dist << -0.25, 0.08, 0.002, -0.003, 0.01;
  const DistanceField field(60, 80, Eigen::Vector2d(70, 10), 2.0);
  ExpectJacobianMatchesNumeric(setup, field);
}

TEST(SegmentSamplesCost, SamplesInsideTheSilhouetteCostNothingAndPullNowhere) {
  const PosedHand setup;
  const DistanceField field(60, 80, Eigen::Vector2d(40, 30), -200.0);
  const ti::SegmentSamplesCost cost = setup.Cost(field);
  const std::vector<const double*> parameters = setup.Parameters();
  const std::size_t n = setup.local_samples.size();
  std::vector<double> residuals(n, -1.0);
  std::vector<std::vector<double>> jacobian_storage;
  std::vector<double*> jacobians;
  for (const auto& v : setup.values) {
    jacobian_storage.emplace_back(n * v.size(), -1.0);
    jacobians.push_back(jacobian_storage.back().data());
  }
  ASSERT_TRUE(cost.Evaluate(parameters.data(), residuals.data(), jacobians.data()));
  for (double r : residuals) EXPECT_EQ(r, 0.0);
  for (const auto& block : jacobian_storage)
    for (double d : block) EXPECT_EQ(d, 0.0);
}

}  // namespace
}  // namespace confluent
