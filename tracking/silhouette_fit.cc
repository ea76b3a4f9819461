// The silhouette fit: the masks prepared as distance fields and contour rays, and the Ceres
// problem over the template's pose and shape (its costs: tracking/segment_costs.h).

#include "tracking/silhouette_fit.h"

#include <ceres/ceres.h>
#include <ceres/cubic_interpolation.h>
#include <ceres/normal_prior.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/cv_interop.h"
#include "core/error.h"
#include "tracking/body_model_impl.h"
#include "tracking/fit_params.h"
#include "tracking/segment_costs.h"

namespace confluent {

namespace ti = tracking_internal;
using Eigen::Matrix3d;
using Eigen::Vector3d;

void SilhouetteFitOptions::Check() const {
  const std::string owner = "SilhouetteFitOptions.";
  RequireOption(downscale >= 0 && downscale <= 16, owner + "downscale", downscale, "in [0, 16]");
  RequireOption(automatic_width >= 16, owner + "automatic_width", automatic_width, ">= 16");
  RequireOption(max_contour_points >= 0, owner + "max_contour_points", max_contour_points, ">= 0");
  RequireOption(rounds >= 1, owner + "rounds", rounds, ">= 1");
  RequireOption(max_iterations >= 1, owner + "max_iterations", max_iterations, ">= 1");
  RequireOption(model_to_image_loss_px > 0, owner + "model_to_image_loss_px", model_to_image_loss_px, "> 0");
  RequireOption(image_to_model_loss_px > 0, owner + "image_to_model_loss_px", image_to_model_loss_px, "> 0");
  RequireOption(image_to_model_weight >= 0, owner + "image_to_model_weight", image_to_model_weight, ">= 0");
  RequireOption(prior_weight >= 0, owner + "prior_weight", prior_weight, ">= 0");
  RequireOption(rest_prior_scale >= 0, owner + "rest_prior_scale", rest_prior_scale, ">= 0");
  RequireOption(shape_prior_weight >= 0, owner + "shape_prior_weight", shape_prior_weight, ">= 0");
  RequireOption(shape_proportion_weight >= 0, owner + "shape_proportion_weight", shape_proportion_weight, ">= 0");
  RequireOption(skirt_prior_weight >= 0, owner + "skirt_prior_weight", skirt_prior_weight, ">= 0");
  RequireOption(section_prior_weight >= 0, owner + "section_prior_weight", section_prior_weight, ">= 0");
  RequireOption(min_section_scale > 0 && min_section_scale <= 1, owner + "min_section_scale", min_section_scale,
                "in (0, 1]");
  RequireOption(max_section_scale >= 1 && max_section_scale <= 3, owner + "max_section_scale", max_section_scale,
                "in [1, 3]");
  RequireOption(depth_offset_prior_weight >= 0, owner + "depth_offset_prior_weight", depth_offset_prior_weight,
                ">= 0");
  RequireOption(max_depth_offset >= 0 && max_depth_offset <= 1, owner + "max_depth_offset", max_depth_offset,
                "in [0, 1]");
  RequireOption(max_mid_bulge >= 0 && max_mid_bulge <= 1, owner + "max_mid_bulge", max_mid_bulge, "in [0, 1]");
  RequireOption(num_threads >= 1, owner + "num_threads", num_threads, ">= 1");
}

// One camera prepared for fitting.
struct PreparedView {
  Camera camera;
  double scale = 1.0;                 // full-resolution pixels per reduced pixel
  int rows = 0, cols = 0;
  std::vector<float> signed_distance;  // reduced px, positive outside the silhouette
  std::unique_ptr<ceres::Grid2D<float, 1>> grid;
  std::unique_ptr<ceres::BiCubicInterpolator<ceres::Grid2D<float, 1>>> interpolator;
  std::vector<Vector3d> ray_origins, ray_directions;  // contour pixels, world
};

struct SilhouetteObservations::Impl {
  std::vector<PreparedView> views;
};

namespace {

// The offset (reduced px) from the centre of contour pixel (x, y) to the silhouette's edge
// nearby. Along each axis with exactly one background 4-neighbour, the edge lies where the
// area coverage, linearly interpolated between the two pixel centres, crosses one half; the
// offset is the foot of the perpendicular on the line through those axis crossings. Without it
// the contour rays would run half a reduced pixel inside the silhouette and the template would
// be fitted that much too thin.
Eigen::Vector2d ContourEdgeOffset(const cv::Mat& coverage, const cv::Mat& binary, int x, int y) {
  auto outside = [&](int xx, int yy) {
    return xx < 0 || yy < 0 || xx >= binary.cols || yy >= binary.rows || !binary.at<uchar>(yy, xx);
  };
  auto value = [&](int xx, int yy) {
    return xx < 0 || yy < 0 || xx >= binary.cols || yy >= binary.rows ? 0.0 : double(coverage.at<uchar>(yy, xx));
  };
  const double a = value(x, y);
  double inv[2] = {0.0, 0.0};  // signed 1 / crossing distance per axis (0: no crossing)
  for (int axis = 0; axis < 2; ++axis) {
    const int dx = axis == 0, dy = axis == 1;
    const bool plus = outside(x + dx, y + dy), minus = outside(x - dx, y - dy);
    if (plus == minus) continue;
    const int sign = plus ? 1 : -1;
    const double b = value(x + sign * dx, y + sign * dy);
    const double t = std::clamp((a - 127.5) / std::max(a - b, 1.0), 0.05, 1.0);
    inv[axis] = sign / t;
  }
  const double norm2 = inv[0] * inv[0] + inv[1] * inv[1];
  if (norm2 == 0.0) return Eigen::Vector2d::Zero();
  return Eigen::Vector2d(inv[0], inv[1]) / norm2;
}

}  // namespace

int FitReductionFactor(int downscale, int mask_width, int automatic_width) {
  if (downscale > 0) return downscale;
  return std::max(1, static_cast<int>(std::lround(mask_width / static_cast<double>(automatic_width))));
}

SilhouetteObservations::SilhouetteObservations(const Rig& rig, const std::vector<Image>& masks,
                                               const std::vector<bool>& use_camera, int downscale,
                                               int max_contour_points, int automatic_width)
    : impl_(std::make_unique<Impl>()) {
  for (int c = 0; c < rig.size(); ++c) {
    if (!use_camera.empty() && !use_camera[c]) continue;
    if (c >= static_cast<int>(masks.size()) || masks[c].empty()) continue;
    const Image& mask = masks[c];
    PreparedView view;
    view.camera = rig.cameras[c];
    const int factor = FitReductionFactor(downscale, mask.width, automatic_width);
    cv::Mat full = AsCvMat(mask);
    cv::Mat small;
    view.cols = std::max(1, mask.width / factor);
    view.rows = std::max(1, mask.height / factor);
    view.scale = static_cast<double>(mask.width) / view.cols;
    cv::resize(full, small, cv::Size(view.cols, view.rows), 0, 0, cv::INTER_AREA);
    const cv::Mat coverage = small.clone();  // area fraction of foreground, 0..255
    cv::threshold(small, small, 127, 255, cv::THRESH_BINARY);
    cv::Mat inside, outside, not_small;
    cv::bitwise_not(small, not_small);
    cv::distanceTransform(small, inside, cv::DIST_L2, 3);        // inside: distance to the background
    cv::distanceTransform(not_small, outside, cv::DIST_L2, 3);   // outside: distance to the silhouette
    view.signed_distance.resize(static_cast<std::size_t>(view.rows) * view.cols);
    for (int y = 0; y < view.rows; ++y)
      for (int x = 0; x < view.cols; ++x)
        view.signed_distance[y * view.cols + x] = std::min(outside.at<float>(y, x), 60.0f) - inside.at<float>(y, x);
    view.grid = std::make_unique<ceres::Grid2D<float, 1>>(view.signed_distance.data(), 0, view.rows, 0, view.cols);
    view.interpolator = std::make_unique<ceres::BiCubicInterpolator<ceres::Grid2D<float, 1>>>(*view.grid);
    // Contour pixels: inside pixels with a 4-neighbour outside.
    std::vector<Eigen::Vector2i> contour;
    for (int y = 0; y < view.rows; ++y)
      for (int x = 0; x < view.cols; ++x) {
        if (!small.at<uchar>(y, x)) continue;
        const bool edge = x == 0 || y == 0 || x + 1 == view.cols || y + 1 == view.rows || !small.at<uchar>(y, x - 1) ||
                          !small.at<uchar>(y, x + 1) || !small.at<uchar>(y - 1, x) || !small.at<uchar>(y + 1, x);
        if (edge) contour.emplace_back(x, y);
      }
    const double step = contour.size() > static_cast<std::size_t>(max_contour_points)
                            ? static_cast<double>(contour.size()) / std::max(1, max_contour_points)
                            : 1.0;
    for (double i = 0; i < contour.size() && max_contour_points > 0; i += step) {
      const Eigen::Vector2i& p = contour[static_cast<std::size_t>(i)];
      const Eigen::Vector2d edge = ContourEdgeOffset(coverage, small, p.x(), p.y());
      const Eigen::Vector2d pixel((p.x() + 0.5 + edge.x()) * view.scale - 0.5, (p.y() + 0.5 + edge.y()) * view.scale - 0.5);
      view.ray_origins.push_back(view.camera.center_in_world());
      view.ray_directions.push_back(view.camera.RayInWorld(pixel));
    }
    impl_->views.push_back(std::move(view));
  }
}

SilhouetteObservations::~SilhouetteObservations() = default;
SilhouetteObservations::SilhouetteObservations(SilhouetteObservations&&) noexcept = default;
SilhouetteObservations& SilhouetteObservations::operator=(SilhouetteObservations&&) noexcept = default;
int SilhouetteObservations::num_used_cameras() const { return static_cast<int>(impl_->views.size()); }

namespace {

using ti::FitParams;
using ti::kShapeBlockSize;
using ti::SegmentsInWorld;
using ti::SegmentWorld;
using ti::TemplateFitSolverOptions;
using ti::ShapeArrays;

// The normalised distance of a ray to a segment's capsule in the world.
double RayCapsuleDistance(const SegmentWorld& w, const Vector3d& origin, const Vector3d& direction) {
  return ti::RayCapsuleDistance(ti::CapsuleAt(w.frame, w.a, w.axis, w.e1, w.e2), origin, direction);
}

bool IsCoarseSegment(int s) {
  return s == int(BodySegment::kHead) || s == int(BodySegment::kNeck) || s == int(BodySegment::kUpperTorso) ||
         s == int(BodySegment::kLowerTorso) || s == int(BodySegment::kLeftThigh) || s == int(BodySegment::kRightThigh);
}

bool IsCoarseJoint(int j) { return j == kJointSpine || j == kJointChest || j == kJointLeftHip || j == kJointRightHip; }

// One Ceres solve over the segments/joints selected by `coarse`.
void SolveStage(const BodyTemplate& body, const SilhouetteObservations::Impl& obs, const SilhouetteFitOptions& options,
                bool coarse, bool fit_shape, FitParams* fp, const FitParams& prior, const double* shape_prior,
                SilhouetteFitSummary* summary, bool first) {
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  const auto segments = SegmentsInWorld(body, *fp);
  const auto chains = ti::SegmentChains(body);
  const Vector3d body_center = segments[int(BodySegment::kLowerTorso)].a;
  std::array<Vector3d, kNumTemplateJoints> fixed_rest;
  {
    double length[kNumBodySegments], girth[kNumBodySegments];
    ShapeArrays(fp->shape, length, girth);
    ti::RestPositions(body, length, girth, &fixed_rest);
  }
  for (const PreparedView& view : obs.views) {
    // Image -> model: assign each contour ray to its nearest segment.
    std::array<std::vector<int>, kNumBodySegments> assigned;
    for (std::size_t i = 0; i < view.ray_origins.size(); ++i) {
      int best = -1;
      double best_d = 1e18;
      for (int s = 0; s < kNumBodySegments; ++s) {
        const SegmentWorld& w = segments[s];
        const double d = RayCapsuleDistance(w, view.ray_origins[i], view.ray_directions[i]);
        if (d < best_d) {
          best_d = d;
          best = s;
        }
      }
      if (best >= 0 && (!coarse || IsCoarseSegment(best))) assigned[best].push_back(static_cast<int>(i));
    }
    const double depth = std::max(0.3, view.camera.PointInCamera(body_center).z());
    const double px_per_m = 0.5 * (view.camera.K(0, 0) + view.camera.K(1, 1)) / view.scale / depth;
    for (int s = 0; s < kNumBodySegments; ++s) {
      if (coarse && !IsCoarseSegment(s)) continue;
      for (int kind = 0; kind < 2; ++kind) {
        if (kind == 1 && (assigned[s].empty() || options.image_to_model_weight <= 0)) continue;
        // The costs, with their Jacobians by hand (segment_costs.h).
        ti::SegmentShapeBlocks shape;
        shape.shape = fit_shape;
        shape.skirt = fit_shape && options.fit_skirt && s == int(BodySegment::kLowerTorso);
        shape.section = fit_shape && options.fit_sections;
        shape.rest = fixed_rest;
        shape.frame = segments[s].frame;
        shape.skirt_values[0] = fp->skirt[0];
        shape.skirt_values[1] = fp->skirt[1];
        shape.section_values.assign(fp->section, fp->section + ti::kSectionBlockSize);
        std::vector<double*> blocks = {fp->root_t, fp->root_aa};
        for (int j : chains[s]) blocks.push_back(fp->dofs[j].data());
        if (shape.shape) blocks.push_back(fp->shape);
        if (shape.skirt) blocks.push_back(fp->skirt);
        if (shape.section) blocks.push_back(fp->section);
        if (kind == 0) {
          // Small segments (head, neck, hands, feet) get every other sample.
          const bool small = s == int(BodySegment::kHead) || s == int(BodySegment::kNeck) ||
                             s == int(BodySegment::kLeftHand) || s == int(BodySegment::kRightHand) ||
                             s == int(BodySegment::kLeftFoot) || s == int(BodySegment::kRightFoot);
          std::vector<SurfaceCoord> samples;
          const auto& all = body.sample_coords();
          for (std::size_t i = 0; i < all.size(); i += small ? 2 : 1) samples.push_back(all[i]);
          problem.AddResidualBlock(
              new ti::SegmentSamplesCost(body, s, chains[s], fp->root_reference, std::move(shape), std::move(samples),
                                         view.camera, view.scale, *view.interpolator),
              new ceres::HuberLoss(options.model_to_image_loss_px), blocks);
        } else {
          std::vector<Vector3d> origins, directions;
          for (int index : assigned[s]) {
            origins.push_back(view.ray_origins[index]);
            directions.push_back(view.ray_directions[index]);
          }
          problem.AddResidualBlock(
              new ti::SegmentRaysCost(body, s, chains[s], fp->root_reference, std::move(shape), std::move(origins),
                                      std::move(directions), px_per_m * options.image_to_model_weight),
              new ceres::CauchyLoss(options.image_to_model_loss_px), blocks);
        }
      }
    }
  }
  if (problem.NumResidualBlocks() == 0) return;
  // Priors and bounds.
  for (int j = 1; j < kNumTemplateJoints; ++j) {
    const int n = body.dofs()[j].num_dof();
    if (n == 0 || !problem.HasParameterBlock(fp->dofs[j].data())) continue;
    double* block = fp->dofs[j].data();
    if (!options.fit_pose || (coarse && !IsCoarseJoint(j))) {
      problem.SetParameterBlockConstant(block);
      continue;
    }
    ti::AddJointPriorAndLimits(body, j, prior.dofs[j].data(), options.prior_weight, block, &problem);
    if (options.max_wrist_palm_bend_rad >= 0 && (j == kJointLeftWrist || j == kJointRightWrist)) {
      const double limit = options.max_wrist_palm_bend_rad;
      block[1] = std::clamp(block[1], -limit, limit);
      problem.SetParameterLowerBound(block, 1, std::max(body.dofs()[j].lower[1], -limit));
      problem.SetParameterUpperBound(block, 1, std::min(body.dofs()[j].upper[1], limit));
    }
    ti::AddJointRestPrior(body, j, options.rest_prior_scale, block, &problem);
  }
  if (!options.fit_pose) {
    problem.SetParameterBlockConstant(fp->root_t);
    problem.SetParameterBlockConstant(fp->root_aa);
  }
  if (fit_shape) {
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(kShapeBlockSize, kShapeBlockSize);
    Eigen::VectorXd b(kShapeBlockSize);
    for (int i = 0; i < kShapeBlockSize; ++i) {
      A(i, i) = options.shape_prior_weight;
      b(i) = shape_prior[i];
    }
    problem.AddResidualBlock(new ceres::NormalPrior(A, b), nullptr, fp->shape);
    if (options.shape_proportion_weight > 0)
      ti::AddShapeProportionPrior(options.shape_proportion_weight, fp->shape, &problem);
    for (int i = 0; i < kShapeBlockSize; ++i) {
      problem.SetParameterLowerBound(fp->shape, i, 0.6 * shape_prior[i]);
      problem.SetParameterUpperBound(fp->shape, i, 1.6 * shape_prior[i]);
    }
  }  // else the costs hold the shape (SegmentShapeBlocks)
  if (problem.HasParameterBlock(fp->section)) {
    // Cross-sections: a pull towards the generic template's, within plausible bodies.
    Eigen::VectorXd generic(ti::kSectionBlockSize);
    for (int i = 0; i < ti::kSectionBlockSize; ++i) generic[i] = ti::DefaultSectionValue(i);
    using ti::SectionKind;
    Eigen::MatrixXd weights = Eigen::MatrixXd::Zero(ti::kSectionBlockSize, ti::kSectionBlockSize);
    for (int i = 0; i < ti::kSectionBlockSize; ++i)
      weights(i, i) = ti::SectionKindOf(i) == SectionKind::kDepthOffset ? options.depth_offset_prior_weight
                                                                      : options.section_prior_weight;
    problem.AddResidualBlock(new ceres::NormalPrior(weights, generic), nullptr, fp->section);
    for (int i = 0; i < ti::kSectionBlockSize; ++i) {
      const SectionKind kind = ti::SectionKindOf(i);
      const double lo = kind == SectionKind::kDepthOffset ? -options.max_depth_offset
                        : kind == SectionKind::kMidBulge  ? -options.max_mid_bulge
                                                          : options.min_section_scale;
      const double hi = kind == SectionKind::kDepthOffset ? options.max_depth_offset
                        : kind == SectionKind::kMidBulge  ? options.max_mid_bulge
                                                          : options.max_section_scale;
      fp->section[i] = std::clamp(fp->section[i], lo, hi);
      problem.SetParameterLowerBound(fp->section, i, lo);
      problem.SetParameterUpperBound(fp->section, i, hi);
    }
  }
  if (problem.HasParameterBlock(fp->skirt)) {
    // A weak pull towards no skirt; the skirt reaches at most to the ground and flares at most
    // to a wide dress (both follow the body's scale).
    const std::array<double, 2> max_skirt = MaxSkirt(shape_prior[0], shape_prior[ti::kNumShapeGroups]);
    problem.AddResidualBlock(new ceres::NormalPrior(Eigen::Matrix2d::Identity() * options.skirt_prior_weight,
                                                    Eigen::Vector2d::Zero()),
                             nullptr, fp->skirt);
    for (int i = 0; i < 2; ++i) {
      fp->skirt[i] = std::clamp(fp->skirt[i], 0.0, max_skirt[i]);
      problem.SetParameterLowerBound(fp->skirt, i, 0.0);
      problem.SetParameterUpperBound(fp->skirt, i, max_skirt[i]);
    }
  }
  const ceres::Solver::Options solver_options = TemplateFitSolverOptions(
      coarse ? std::max(1, options.max_iterations / 2) : options.max_iterations, options.num_threads, 1e-5, 1e-6);
  ceres::Solver::Summary solver_summary;
  ceres::Solve(solver_options, &problem, &solver_summary);
  if (first) summary->initial_cost = solver_summary.initial_cost;
  summary->final_cost = solver_summary.final_cost;
  summary->iterations += static_cast<int>(solver_summary.iterations.size()) - 1;
  summary->converged = solver_summary.termination_type == ceres::CONVERGENCE;
}

}  // namespace

SilhouetteFitSummary FitTemplateToSilhouettes(const BodyTemplate& body, const SilhouetteObservations& observations,
                                              const SilhouetteFitOptions& options, BodyShape* shape,
                                              TemplatePose* pose, const TemplatePose* prior) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  SilhouetteFitSummary summary;
  summary.num_cameras = observations.num_used_cameras();
  if (summary.num_cameras == 0) return summary;
  const auto& obs = observations.impl();
  // Shape: one value per group (left and right share), the mean of the group's segments.
  FitParams fp;
  double shape_prior[kShapeBlockSize];
  ti::ShapeToParams(*shape, fp.shape, fp.skirt, fp.section);
  // The shape prior: the mean scale of lengths and of girths (a uniformly scaled body).
  double mean_l = 0, mean_g = 0;
  for (int g = 0; g < ti::kNumShapeGroups; ++g) {
    mean_l += fp.shape[g] / ti::kNumShapeGroups;
    mean_g += fp.shape[ti::kNumShapeGroups + g] / ti::kNumShapeGroups;
  }
  for (int g = 0; g < ti::kNumShapeGroups; ++g) {
    shape_prior[g] = mean_l;
    shape_prior[ti::kNumShapeGroups + g] = mean_g;
  }
  for (int k = 0; k < 3; ++k) fp.root_t[k] = pose->root_translation[k];
  fp.root_reference = ti::AngleAxisMatrix(pose->root_rotation.data());
  body.ClampToLimits(pose);
  fp.dofs = pose->dofs;
  FitParams prior_params = fp;
  if (prior) prior_params.dofs = prior->dofs;

  bool first = true;
  if (options.coarse_to_fine && options.fit_pose) {
    SolveStage(body, obs, options, true, false, &fp, prior_params, shape_prior, &summary, first);
    first = false;
  }
  for (int round = 0; round < options.rounds; ++round) {
    SolveStage(body, obs, options, false, options.fit_shape, &fp, prior_params, shape_prior, &summary, first);
    first = false;
    // Fold the root rotation increment into the reference.
    const Matrix3d R = ti::AngleAxisMatrix(fp.root_aa) * fp.root_reference;
    fp.root_reference = R;
    fp.root_aa[0] = fp.root_aa[1] = fp.root_aa[2] = 0.0;
  }
  {
    const Matrix3d R = ti::AngleAxisMatrix(fp.root_aa) * fp.root_reference;
    const Eigen::AngleAxisd aa(R);
    pose->root_rotation = aa.angle() * aa.axis();
  }
  pose->root_translation = Vector3d(fp.root_t[0], fp.root_t[1], fp.root_t[2]);
  pose->dofs = fp.dofs;
  if (options.fit_shape) {
    *shape = ti::ParamsToShape(fp.shape, fp.skirt, fp.section);
  }
  // Residual statistics at the solution.
  {
    fp.root_reference = ti::AngleAxisMatrix(pose->root_rotation.data());
    const auto segments = SegmentsInWorld(body, fp);
    double outside = 0, contour = 0;
    long n_out = 0, n_contour = 0;
    double length[kNumBodySegments], girth[kNumBodySegments];
    ShapeArrays(fp.shape, length, girth);
    std::array<Vector3d, kNumTemplateJoints> rest;
    ti::RestPositions(body, length, girth, &rest);
    for (const PreparedView& view : obs.views) {
      for (int s = 0; s < kNumBodySegments; ++s) {
        const SegmentWorld& w = segments[s];
        const int joint = body.segments()[s].joint;
        for (const SurfaceCoord& sc : body.sample_coords()) {
          const Vector3d X = w.P + w.R * (w.frame.Point(sc) - rest[joint]);
          const Eigen::Vector2d px = view.camera.Project(X);
          double sd;
          view.interpolator->Evaluate((px.y() + 0.5) / view.scale - 0.5, (px.x() + 0.5) / view.scale - 0.5, &sd);
          outside += std::max(sd, 0.0);
          ++n_out;
        }
      }
      const double depth = std::max(0.3, view.camera.PointInCamera(segments[int(BodySegment::kLowerTorso)].a).z());
      const double px_per_m = 0.5 * (view.camera.K(0, 0) + view.camera.K(1, 1)) / view.scale / depth;
      for (std::size_t i = 0; i < view.ray_origins.size(); ++i) {
        double best = 1e18;
        int best_s = 0;
        for (int s = 0; s < kNumBodySegments; ++s) {
          const SegmentWorld& w = segments[s];
          const double d = RayCapsuleDistance(w, view.ray_origins[i], view.ray_directions[i]);
          if (d < best) {
            best = d;
            best_s = s;
          }
        }
        const auto& f = segments[best_s].frame;
        contour += std::abs(best - 1.0) * 0.25 * (f.rax + f.ray + f.rbx + f.rby) * px_per_m;
        ++n_contour;
      }
    }
    summary.mean_outside_px = n_out ? outside / n_out : 0.0;
    summary.mean_contour_px = n_contour ? contour / n_contour : 0.0;
  }
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace confluent
