// The silhouette costs' hand-written Jacobians against Ceres' numeric differentiation
// (GradientChecker), by the pose alone and by pose, shape, skirt and cross-sections; the
// samples' residuals against the camera's own projection of the posed samples into a distance
// field of known form, the rays' against rays placed at known distances from the capsule.

#include "tracking/segment_costs.h"

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
  std::vector<float> values;
  std::unique_ptr<ceres::Grid2D<float, 1>> grid;
  std::unique_ptr<ti::SignedDistanceInterpolator> interpolator;
  DistanceField(int rows, int cols, Eigen::Vector2d centre, double offset) {
    for (int y = 0; y < rows; ++y)
      for (int x = 0; x < cols; ++x) values.push_back(float((Eigen::Vector2d(x, y) - centre).norm() + offset));
    grid = std::make_unique<ceres::Grid2D<float, 1>>(values.data(), 0, rows, 0, cols);
    interpolator = std::make_unique<ti::SignedDistanceInterpolator>(*grid);
  }
};

// One segment, posed, with its shape held or as parameter blocks.
struct PosedSegment {
  BodyTemplate body;
  int segment;
  std::vector<int> chain;
  ti::SegmentShapeBlocks shape;
  Eigen::Matrix3d root_reference;
  Camera camera = testing::CameraRing(1, 320, 240).cameras[0];
  double scale = 4.0;  // 80 x 60 reduced pixels
  // Parameter values: root translation, root rotation, the chain's DOFs, then the shape blocks.
  std::vector<std::vector<double>> values;
  std::vector<double> shape_values, skirt_values, section_values;

  PosedSegment(BodySegment which, bool fit_shape, bool fit_skirt = false)
      : segment(int(which)), chain(ti::SegmentChains(body)[segment]) {
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
    // A body a little off the generic one: every scale and cross-section value differs.
    for (int i = 0; i < ti::kShapeBlockSize; ++i) shape_values.push_back(0.9 + 0.02 * i);
    skirt_values = {0.12, 0.05};
    for (int i = 0; i < ti::kSectionBlockSize; ++i)
      section_values.push_back(ti::DefaultSectionValue(i) + 0.01 * (i % 7) - 0.02);
    shape.shape = fit_shape;
    shape.skirt = fit_shape && fit_skirt;
    shape.section = fit_shape;
    shape.skirt_values[0] = skirt_values[0];
    shape.skirt_values[1] = skirt_values[1];
    shape.section_values = section_values;
    shape.frame = Capsule(&shape.rest);
    if (shape.shape) values.push_back(shape_values);
    if (shape.skirt) values.push_back(skirt_values);
    if (shape.section) values.push_back(section_values);
  }
  // The segment's capsule at rest and the rest joints, from the shape values.
  ti::SegmentFrame<double> Capsule(std::array<Eigen::Vector3d, kNumTemplateJoints>* rest) const {
    double length[kNumBodySegments], girth[kNumBodySegments];
    ti::ShapeArrays(shape_values.data(), length, girth);
    ti::RestPositions(body, length, girth, rest);
    return ti::MakeSegmentFrame(body, segment, *rest, length, girth, skirt_values.data(),
                                ti::SegmentSection(section_values.data(), segment));
  }
  std::vector<const double*> Parameters() const {
    std::vector<const double*> pointers;
    for (const auto& v : values) pointers.push_back(v.data());
    return pointers;
  }
  ti::SegmentSamplesCost Cost(const DistanceField& field) const {
    return ti::SegmentSamplesCost(body, segment, chain, root_reference, shape, body.sample_coords(), camera, scale,
                                  *field.interpolator);
  }
  // The capsule at rest and the segment's world transform (rest joint of the segment -> P).
  struct Posed {
    ti::SegmentFrame<double> frame;
    Eigen::Vector3d joint_rest, P;
    Eigen::Matrix3d R;
    Eigen::Vector3d World(const Eigen::Vector3d& rest_point) const { return R * (rest_point - joint_rest) + P; }
  };
  Posed Pose() const {
    std::array<Eigen::Vector3d, kNumTemplateJoints> rest;
    Posed posed;
    posed.frame = Capsule(&rest);
    const double* joint_params[kNumTemplateJoints] = {};
    for (std::size_t i = 0; i < chain.size(); ++i) joint_params[chain[i]] = values[2 + i].data();
    const int joint = body.segments()[segment].joint;
    posed.joint_rest = rest[joint];
    ti::JointWorldTransform(body, joint, rest, values[0].data(), values[1].data(), root_reference, joint_params,
                            &posed.R, &posed.P);
    return posed;
  }
  // The samples in the world, posed by the parameters.
  std::vector<Eigen::Vector3d> WorldSamples() const {
    const Posed posed = Pose();
    std::vector<Eigen::Vector3d> world;
    for (const SurfaceCoord& sc : body.sample_coords()) world.push_back(posed.World(posed.frame.Point(sc)));
    return world;
  }
};

void ExpectJacobianMatchesNumeric(const PosedSegment& setup, const ceres::CostFunction& cost) {
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
    const double largest = numeric.cwiseAbs().maxCoeff();
    EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-6 * std::max(largest, 1e-3))
        << "block " << b << "\n" << results.error_log;
    EXPECT_GT(largest, 1e-3) << "block " << b << " does not move the residuals";
  }
}

void ExpectJacobianMatchesNumeric(const PosedSegment& setup, const DistanceField& field) {
  const ti::SegmentSamplesCost cost = setup.Cost(field);
  ExpectJacobianMatchesNumeric(setup, cost);
  const std::vector<const double*> parameters = setup.Parameters();
  // The residuals: the field where the camera projects each posed sample.
  std::vector<double> residuals(setup.body.sample_coords().size());
  ASSERT_TRUE(cost.Evaluate(parameters.data(), residuals.data(), nullptr));
  const std::vector<Eigen::Vector3d> world = setup.WorldSamples();
  for (std::size_t i = 0; i < world.size(); ++i) {
    const Eigen::Vector2d px = setup.camera.Project(world[i]);
    double sd;
    field.interpolator->Evaluate((px.y() + 0.5) / setup.scale - 0.5, (px.x() + 0.5) / setup.scale - 0.5, &sd);
    EXPECT_NEAR(residuals[i], std::max(sd, 0.0), 1e-9) << "sample " << i;
  }
}

TEST(SegmentSamplesCost, ThePoseJacobianMatchesNumericDifferentiationOutsideTheSilhouette) {
  const PosedSegment hand(BodySegment::kRightHand, false);
  const DistanceField field(60, 80, Eigen::Vector2d(20, 45), 3.0);
  ExpectJacobianMatchesNumeric(hand, field);
  // The field is positive everywhere: every sample has a residual that moves with the pose.
  std::vector<double> residuals(hand.body.sample_coords().size());
  ASSERT_TRUE(hand.Cost(field).Evaluate(hand.Parameters().data(), residuals.data(), nullptr));
  for (double r : residuals) EXPECT_GT(r, 3.0);
}

TEST(SegmentSamplesCost, ThePoseJacobianMatchesNumericDifferentiationThroughLensDistortion) {
  PosedSegment hand(BodySegment::kRightHand, false);
  hand.camera.dist << -0.25, 0.08, 0.002, -0.003, 0.01;
  ExpectJacobianMatchesNumeric(hand, DistanceField(60, 80, Eigen::Vector2d(70, 10), 2.0));
}

TEST(SegmentSamplesCost, ShapeSkirtAndSectionJacobiansMatchNumericDifferentiation) {
  PosedSegment hips(BodySegment::kLowerTorso, true, true);
  hips.camera.dist << 0.1, -0.02, 0.0, 0.001, 0.0;
  ExpectJacobianMatchesNumeric(hips, DistanceField(60, 80, Eigen::Vector2d(10, 50), 1.0));
  const PosedSegment forearm(BodySegment::kLeftForearm, true);
  ExpectJacobianMatchesNumeric(forearm, DistanceField(60, 80, Eigen::Vector2d(75, 55), 1.0));
}

// Rays across the middle of the posed capsule, along e2, at `k` times its radius along e1 from
// the axis: normalised distance k, residual (k - 1) times the mean radius there times the weight.
TEST(SegmentRaysCost, RaysAtKnownDistancesGiveTheirResidualsAndJacobiansMatchNumericDifferentiation) {
  for (const bool fit_shape : {false, true}) {
    const PosedSegment forearm(BodySegment::kLeftForearm, fit_shape);
    const PosedSegment::Posed posed = forearm.Pose();
    const ti::SegmentFrame<double>& frame = posed.frame;
    double rx, ry;
    frame.Radii(0.5, &rx, &ry);
    const Eigen::Vector3d middle = frame.a + frame.axis * (0.5 * frame.length);
    const Eigen::Vector3d direction = forearm.Pose().R * frame.e2;
    const std::vector<double> distances = {0.4, 0.9, 1.3, 2.5};
    std::vector<Eigen::Vector3d> origins, directions;
    for (double k : distances) {
      origins.push_back(posed.World(middle + frame.e1 * (k * rx) - frame.e2 * 2.0));
      directions.push_back(direction);
    }
    const double weight = 300.0;
    const ti::SegmentRaysCost cost(forearm.body, forearm.segment, forearm.chain, forearm.root_reference, forearm.shape,
                                   origins, directions, weight);
    std::vector<double> residuals(distances.size());
    ASSERT_TRUE(cost.Evaluate(forearm.Parameters().data(), residuals.data(), nullptr));
    for (std::size_t i = 0; i < distances.size(); ++i)
      EXPECT_NEAR(residuals[i], (distances[i] - 1.0) * 0.5 * (rx + ry) * weight, 1e-6) << "ray " << i;
    ExpectJacobianMatchesNumeric(forearm, cost);
  }
}

TEST(SegmentSamplesCost, SamplesInsideTheSilhouetteCostNothingAndPullNowhere) {
  const PosedSegment thigh(BodySegment::kLeftThigh, true);
  const DistanceField field(60, 80, Eigen::Vector2d(40, 30), -200.0);
  const ti::SegmentSamplesCost cost = thigh.Cost(field);
  const std::vector<const double*> parameters = thigh.Parameters();
  const std::size_t n = thigh.body.sample_coords().size();
  std::vector<double> residuals(n, -1.0);
  std::vector<std::vector<double>> jacobian_storage;
  std::vector<double*> jacobians;
  for (const auto& v : thigh.values) {
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
