#pragma once
// INTERNAL (tracking/*.cc and their tests): the silhouette fit's two costs of one segment in one
// camera, with their Jacobians by hand.
// - SegmentSamplesCost (model -> image): each surface sample of the segment is posed and
//   projected; its residual is the silhouette's signed distance there when positive (outside),
//   else 0.
// - SegmentRaysCost (image -> model): each contour ray assigned to the segment; its residual is
//   the ray's distance to the segment's capsule, relative to the capsule's radius there.
// Both depend on the pose and the shape only through the segment's capsule (its end, axes and
// radii: 20 numbers, SegmentCapsuleCost), so those are differentiated once per evaluation
// (Jets) and each residual is chained through them: a sample costs a few dozen multiplications
// (none inside the silhouette), a ray a 20-wide Jet evaluation. The automatic-differentiation
// functor they replace evaluated every residual in 18-wide Jets through the whole kinematic
// chain, in up to five passes when the shape was fitted.

#include <ceres/cubic_interpolation.h>
#include <ceres/dynamic_cost_function.h>

#include <Eigen/Core>
#include <array>
#include <vector>

#include "calib/camera.h"
#include "tracking/body_model_impl.h"
#include "tracking/body_template.h"

namespace confluent::tracking_internal {

using SignedDistanceInterpolator = ceres::BiCubicInterpolator<ceres::Grid2D<float, 1>>;

// A capsule's 20 values: its end A (3), axis (3), e1 (3) and e2 (3), then its length, cap_a,
// cap_b, rax, rbx, ray, rby and bulge (SegmentFrame's). A surface coordinate (s, c, x, y) of
// SegmentFrame::Point is at A + axis (length s + cap c) + e1 rx(s) x + e2 ry(s) y.
constexpr int kNumCapsuleValues = 20;
using CapsuleValues = Eigen::Matrix<double, kNumCapsuleValues, 1>;
// The capsule with `frame`'s length and radii, its end at `a` and its axes `axis`, `e1`, `e2`.
CapsuleValues CapsuleAt(const SegmentFrame<double>& frame, const Eigen::Vector3d& a, const Eigen::Vector3d& axis,
                        const Eigen::Vector3d& e1, const Eigen::Vector3d& e2);
// The normalised distance (1 on the surface) from the ray `origin` + t `direction` (unit) to a
// capsule.
double RayCapsuleDistance(const CapsuleValues& capsule, const Eigen::Vector3d& origin,
                          const Eigen::Vector3d& direction);

// What of the segment's shape is a parameter block of the cost, and the values of the rest.
struct SegmentShapeBlocks {
  bool shape = false;    // the shape block (kShapeBlockSize: length, then girth scale per group)
  bool skirt = false;    // the skirt block (2), after the shape block; only with it
  bool section = false;  // the section block (kSectionBlockSize), last; only with the shape block
  // Without the shape block: the rest joints and the segment's capsule.
  std::array<Eigen::Vector3d, kNumTemplateJoints> rest{};
  SegmentFrame<double> frame{};
  // With the shape block: the skirt and the cross-sections that are not blocks.
  double skirt_values[2] = {0.0, 0.0};
  std::vector<double> section_values;  // kSectionBlockSize values
};

// Residuals that depend on the parameters only through the segment's capsule, expressed in the
// frame x' = rotation x + translation. Parameter blocks, in order: root translation (3), root
// rotation vector (3), the DOF blocks of `chain_joints` (the joints with DOFs from the root to
// the segment's joint), then the shape, skirt and section blocks that `shape` names.
class SegmentCapsuleCost : public ceres::DynamicCostFunction {
 public:
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const final;

  static constexpr int kMaxPoseParameters = 24;
  static constexpr int kMaxParameters = 88;

 protected:
  // Throws std::invalid_argument when the blocks hold more than kMaxParameters values.
  SegmentCapsuleCost(const BodyTemplate& body, int segment, std::vector<int> chain_joints,
                     const Eigen::Matrix3d& root_reference, SegmentShapeBlocks shape,
                     const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation, int num_residuals);
  using CapsuleGradient = Eigen::Matrix<double, 1, kNumCapsuleValues>;
  // Residual `i` for the capsule; when `gradient` is not null, its derivatives by the capsule's
  // values. Returns false where the residual does not depend on the capsule (then 0 rows).
  virtual bool Residual(int i, const CapsuleValues& capsule, double* residual, CapsuleGradient* gradient) const = 0;

 private:
  using CapsuleJacobian = Eigen::Matrix<double, kNumCapsuleValues, Eigen::Dynamic>;
  template <typename T>
  void Capsule(T const* const* p, T* values) const;
  template <int N>
  void DifferentiateCapsule(double const* const* parameters, CapsuleValues* values, CapsuleJacobian* jacobian) const;

  const BodyTemplate& body_;
  int segment_;
  int joint_;
  std::vector<int> chain_joints_;
  Eigen::Matrix3d root_reference_;
  SegmentShapeBlocks shape_;
  Eigen::Matrix3d rotation_;
  Eigen::Vector3d translation_;
  int num_parameters_ = 6;
};

class SegmentSamplesCost : public SegmentCapsuleCost {
 public:
  // `distance` is sampled in reduced pixels: pixel p of the camera is at (p + 0.5) / `scale` - 0.5.
  SegmentSamplesCost(const BodyTemplate& body, int segment, std::vector<int> chain_joints,
                     const Eigen::Matrix3d& root_reference, SegmentShapeBlocks shape,
                     std::vector<SurfaceCoord> samples, const Camera& camera, double scale,
                     const SignedDistanceInterpolator& distance);

 private:
  bool Residual(int i, const CapsuleValues& capsule, double* residual, CapsuleGradient* gradient) const override;

  std::vector<SurfaceCoord> samples_;
  Camera camera_;
  double scale_;
  const SignedDistanceInterpolator& distance_;
};

class SegmentRaysCost : public SegmentCapsuleCost {
 public:
  // Rays in the world, unit directions; each residual is (distance - 1) times the mean radius
  // where the ray passes, times `weight` (reduced pixels per metre at the body, times the
  // term's weight).
  SegmentRaysCost(const BodyTemplate& body, int segment, std::vector<int> chain_joints,
                  const Eigen::Matrix3d& root_reference, SegmentShapeBlocks shape,
                  std::vector<Eigen::Vector3d> origins, std::vector<Eigen::Vector3d> directions, double weight);

 private:
  bool Residual(int i, const CapsuleValues& capsule, double* residual, CapsuleGradient* gradient) const override;

  std::vector<Eigen::Vector3d> origins_, directions_;
  double weight_;
};

}  // namespace confluent::tracking_internal
