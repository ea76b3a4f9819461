#pragma once
// INTERNAL (tracking/*.cc only): the parameter blocks shared by the template fits (silhouettes
// and scan registration) and the segments' world frames they imply.

#include <ceres/dynamic_cost_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <Eigen/Core>
#include <array>
#include <vector>

#include "tracking/body_model_impl.h"
#include "tracking/body_template.h"

namespace confluent::tracking_internal {

// Solver options of the template fits: dense normal equations, silent, with these limits.
ceres::Solver::Options TemplateFitSolverOptions(int max_iterations, int num_threads, double function_tolerance,
                                                double parameter_tolerance);

// Length and girth scale per shape group.
constexpr int kShapeBlockSize = 2 * kNumShapeGroups;
// Cross-section depth, taper, depth offset and bulge per shape group (BodyShape::depth_scale,
// taper_scale, depth_offset, mid_bulge), in that order.
constexpr int kSectionBlockSize = 4 * kNumShapeGroups;
// What a section block's entry is, by its position.
enum class SectionKind { kDepth, kTaper, kDepthOffset, kMidBulge };
constexpr SectionKind SectionKindOf(int i) { return static_cast<SectionKind>(i / kNumShapeGroups); }

// The parameter vectors of a fit: world_from_pelvis = R(root_aa) * root_reference.
struct FitParams {
  double root_t[3] = {0, 0, 0};
  double root_aa[3] = {0, 0, 0};
  Eigen::Matrix3d root_reference = Eigen::Matrix3d::Identity();
  std::array<std::array<double, 3>, kNumTemplateJoints> dofs{};
  double shape[kShapeBlockSize] = {};
  double skirt[2] = {0.0, 0.0};  // BodyShape::skirt_length_m, skirt_flare_m (lower torso only)
  double section[kSectionBlockSize] = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};  // offsets, bulges 0
};
static_assert(kSectionBlockSize == 40, "FitParams::section's initialiser lists depth and taper 1, the rest 0");

// Adds to `problem` a prior towards human proportions on the shape block `shape`: each group's
// length (girth) scale towards the mean of the current length (girth) scales, with `weight`.
// The overall size stays free.
void AddShapeProportionPrior(double weight, double* shape, ceres::Problem* problem);

// Per-segment length and girth scales from a shape block.
template <typename T>
void ShapeArrays(const T* shape, T* length, T* girth) {
  for (int s = 0; s < kNumBodySegments; ++s) {
    length[s] = shape[kSegmentGroup[s]];
    girth[s] = shape[kNumShapeGroups + kSegmentGroup[s]];
  }
}
// Segment `segment`'s cross-section in a section block.
template <typename T>
Section<T> SegmentSection(const T* block, int segment) {
  const int g = kSegmentGroup[segment];
  return {block[g], block[kNumShapeGroups + g], block[2 * kNumShapeGroups + g], block[3 * kNumShapeGroups + g]};
}
// The default cross-section values of a section block's entry `i` (1, 1, 0, 0 per kind).
inline double DefaultSectionValue(int i) {
  return SectionKindOf(i) == SectionKind::kDepth || SectionKindOf(i) == SectionKind::kTaper ? 1.0 : 0.0;
}
// The shape block of `shape` (group means) and back; `skirt` (2 values, may be null) carries
// the skirt DOFs, `section` (kSectionBlockSize values, may be null) the cross-sections.
void ShapeToParams(const BodyShape& shape, double* params, double* skirt = nullptr, double* section = nullptr);
BodyShape ParamsToShape(const double* params, const double* skirt = nullptr, const double* section = nullptr);
// The pose the parameters describe, and parameters for a pose (root_aa zero, the rotation in
// root_reference).
TemplatePose ParamsToPose(const FitParams& fp);
void PoseToParams(const TemplatePose& pose, FitParams* fp);

// One segment's capsule frame in the world for the current parameters.
struct SegmentWorld {
  SegmentFrame<double> frame;
  Eigen::Vector3d a, axis, e1, e2;
  Eigen::Matrix3d R;
  Eigen::Vector3d P;
};
std::array<SegmentWorld, kNumBodySegments> SegmentsInWorld(const BodyTemplate& body, const FitParams& fp);

// The joints with DOFs on the chain from the root to each segment's joint, root first.
std::array<std::vector<int>, kNumBodySegments> SegmentChains(const BodyTemplate& body);

// Declares the parameter blocks of a segment cost on `cost` (root translation, root rotation,
// the DOFs of `chain`, the shape) and returns the matching pointers into `fp`.
std::vector<double*> AddSegmentParameterBlocks(const BodyTemplate& body, const std::vector<int>& chain, FitParams* fp,
                                               ceres::DynamicCostFunction* cost);

// Joint `joint`'s DOF block: a prior of `prior_weight` (per radian) towards `prior_values`
// when positive, then the values clamped into the joint limits, which become the bounds.
void AddJointPriorAndLimits(const BodyTemplate& body, int joint, const double* prior_values, double prior_weight,
                            double* block, ceres::Problem* problem);

// Joint `joint`'s pull towards its rest angles, JointDof::rest_weight times `scale` (nothing
// when every weight is 0).
void AddJointRestPrior(const BodyTemplate& body, int joint, double scale, double* block, ceres::Problem* problem);

}  // namespace confluent::tracking_internal
