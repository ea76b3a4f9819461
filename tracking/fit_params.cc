#include "tracking/fit_params.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <ceres/loss_function.h>
#include <ceres/normal_prior.h>

namespace confluent::tracking_internal {

using Eigen::Matrix3d;
using Eigen::Vector3d;

void AddShapeProportionPrior(double weight, double* shape, ceres::Problem* problem) {
  constexpr int n = kNumShapeGroups;
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(kShapeBlockSize, kShapeBlockSize);
  for (int half = 0; half < 2; ++half)
    P.block(half * n, half * n, n, n) = weight * (Eigen::MatrixXd::Identity(n, n) - Eigen::MatrixXd::Constant(n, n, 1.0 / n));
  problem->AddResidualBlock(new ceres::NormalPrior(P, Eigen::VectorXd::Zero(kShapeBlockSize)), nullptr, shape);
}

void ShapeToParams(const BodyShape& shape, double* params, double* skirt, double* section) {
  if (skirt) {
    skirt[0] = shape.skirt_length_m;
    skirt[1] = shape.skirt_flare_m;
  }
  for (int g = 0; g < kNumShapeGroups; ++g) {
    double l = 0, gi = 0, depth = 0, taper = 0, offset = 0, bulge = 0;
    int n = 0;
    for (int s = 0; s < kNumBodySegments; ++s)
      if (kSegmentGroup[s] == g) {
        l += shape.length_scale[s];
        gi += shape.girth_scale[s];
        depth += shape.depth_scale[s];
        taper += shape.taper_scale[s];
        offset += shape.depth_offset[s];
        bulge += shape.mid_bulge[s];
        ++n;
      }
    params[g] = l / n;
    params[kNumShapeGroups + g] = gi / n;
    if (section) {
      section[g] = depth / n;
      section[kNumShapeGroups + g] = taper / n;
      section[2 * kNumShapeGroups + g] = offset / n;
      section[3 * kNumShapeGroups + g] = bulge / n;
    }
  }
}

BodyShape ParamsToShape(const double* params, const double* skirt, const double* section) {
  BodyShape shape;
  ShapeArrays(params, shape.length_scale.data(), shape.girth_scale.data());
  if (skirt) {
    shape.skirt_length_m = skirt[0];
    shape.skirt_flare_m = skirt[1];
  }
  if (section)
    for (int s = 0; s < kNumBodySegments; ++s) {
      const Section<double> v = SegmentSection(section, s);
      shape.depth_scale[s] = v.depth;
      shape.taper_scale[s] = v.taper;
      shape.depth_offset[s] = v.offset;
      shape.mid_bulge[s] = v.bulge;
    }
  return shape;
}

TemplatePose ParamsToPose(const FitParams& fp) {
  TemplatePose pose;
  const Eigen::AngleAxisd aa(Matrix3d(AngleAxisMatrix(fp.root_aa) * fp.root_reference));
  pose.root_rotation = aa.angle() * aa.axis();
  pose.root_translation = Vector3d(fp.root_t[0], fp.root_t[1], fp.root_t[2]);
  pose.dofs = fp.dofs;
  return pose;
}

void PoseToParams(const TemplatePose& pose, FitParams* fp) {
  for (int k = 0; k < 3; ++k) fp->root_t[k] = pose.root_translation[k];
  fp->root_aa[0] = fp->root_aa[1] = fp->root_aa[2] = 0.0;
  fp->root_reference = AngleAxisMatrix(pose.root_rotation.data());
  fp->dofs = pose.dofs;
}

std::array<SegmentWorld, kNumBodySegments> SegmentsInWorld(const BodyTemplate& body, const FitParams& fp) {
  double length[kNumBodySegments], girth[kNumBodySegments];
  ShapeArrays(fp.shape, length, girth);
  std::array<Vector3d, kNumTemplateJoints> rest;
  RestPositions(body, length, girth, &rest);
  const double* jp[kNumTemplateJoints];
  for (int j = 0; j < kNumTemplateJoints; ++j) jp[j] = fp.dofs[j].data();
  std::array<SegmentWorld, kNumBodySegments> out;
  for (int s = 0; s < kNumBodySegments; ++s) {
    SegmentWorld& w = out[s];
    const int joint = body.segments()[s].joint;
    JointWorldTransform(body, joint, rest, fp.root_t, fp.root_aa, fp.root_reference, jp, &w.R, &w.P);
    w.frame = MakeSegmentFrame(body, s, rest, length, girth, fp.skirt, SegmentSection(fp.section, s));
    w.a = w.P + w.R * (w.frame.a - rest[joint]);
    w.axis = w.R * w.frame.axis;
    w.e1 = w.R * w.frame.e1;
    w.e2 = w.R * w.frame.e2;
  }
  return out;
}

std::array<std::vector<int>, kNumBodySegments> SegmentChains(const BodyTemplate& body) {
  std::array<std::vector<int>, kNumBodySegments> chains;
  for (int s = 0; s < kNumBodySegments; ++s) {
    std::vector<int> chain;
    for (int j = body.segments()[s].joint; j > 0; j = body.parents()[j])
      if (body.dofs()[j].type != JointType::kFixed) chain.push_back(j);
    std::reverse(chain.begin(), chain.end());
    chains[s] = chain;
  }
  return chains;
}

std::vector<double*> AddSegmentParameterBlocks(const BodyTemplate& body, const std::vector<int>& chain, FitParams* fp,
                                               ceres::DynamicCostFunction* cost) {
  std::vector<double*> blocks = {fp->root_t, fp->root_aa};
  cost->AddParameterBlock(3);
  cost->AddParameterBlock(3);
  for (int j : chain) {
    cost->AddParameterBlock(body.dofs()[j].num_dof());
    blocks.push_back(fp->dofs[j].data());
  }
  cost->AddParameterBlock(kShapeBlockSize);
  blocks.push_back(fp->shape);
  return blocks;
}

void AddJointPriorAndLimits(const BodyTemplate& body, int joint, const double* prior_values, double prior_weight,
                            double* block, ceres::Problem* problem) {
  const JointDof& dof = body.dofs()[joint];
  const int n = dof.num_dof();
  if (prior_weight > 0) {
    const Eigen::MatrixXd A = Eigen::MatrixXd::Identity(n, n) * prior_weight;
    const Eigen::VectorXd b = Eigen::Map<const Eigen::VectorXd>(prior_values, n);
    problem->AddResidualBlock(new ceres::NormalPrior(A, b), nullptr, block);
  }
  for (int k = 0; k < n; ++k) {
    block[k] = std::clamp(block[k], dof.lower[k], dof.upper[k]);
    problem->SetParameterLowerBound(block, k, dof.lower[k]);
    problem->SetParameterUpperBound(block, k, dof.upper[k]);
  }
}

void AddJointRestPrior(const BodyTemplate& body, int joint, double scale, double* block, ceres::Problem* problem) {
  const JointDof& dof = body.dofs()[joint];
  const int n = dof.num_dof();
  if (scale == 0.0 || std::all_of(dof.rest_weight.begin(), dof.rest_weight.begin() + n, [](double w) { return w == 0.0; }))
    return;  // every joint but the wrists, in every frame's fit: no allocation
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < n; ++k) A(k, k) = dof.rest_weight[k] * scale;
  ceres::LossFunction* loss = nullptr;
  if (dof.rest_fade_rad > 0) {
    const double max_weight = A.diagonal().maxCoeff();
    loss = new ceres::CauchyLoss(max_weight * dof.rest_fade_rad);
  }
  problem->AddResidualBlock(new ceres::NormalPrior(A, Eigen::VectorXd::Zero(n)), loss, block);
}

ceres::Solver::Options TemplateFitSolverOptions(int max_iterations, int num_threads, double function_tolerance,
                                                double parameter_tolerance) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  options.max_num_iterations = max_iterations;
  options.num_threads = num_threads;
  options.logging_type = ceres::SILENT;
  options.function_tolerance = function_tolerance;
  options.parameter_tolerance = parameter_tolerance;
  return options;
}

}  // namespace confluent::tracking_internal
