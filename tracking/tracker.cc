#include "tracking/tracker.h"

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <chrono>
#include <ctime>
#include <cmath>
#include <functional>
#include <string_view>

#include "calib/camera.h"
#include "core/statistics.h"
#include "core/error.h"
#include "core/parallel.h"
#include "silhouette/overlap.h"
#include "tracking/landmark_limbs.h"
#include "tracking/limb_hypotheses.h"
#include "tracking/tracker_flags.h"

namespace confluent {

using namespace tracker_flags;

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// Appends `value` to `window`, dropping its oldest values beyond `size`.
void AppendToWindow(std::vector<double>* window, double value, int size) {
  window->push_back(value);
  if (window->size() > static_cast<std::size_t>(size)) window->erase(window->begin());
}

Matrix3d RotationOf(const Vector3d& aa) {
  const double angle = aa.norm();
  if (angle < 1e-15) return Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, aa / angle).toRotationMatrix();
}

Vector3d RotationVector(const Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

// `shape` with every girth and the skirt's flare grown by `fraction`.
BodyShape InflatedGirths(const BodyShape& shape, double fraction) {
  BodyShape inflated = shape;
  for (double& girth : inflated.girth_scale) girth *= 1.0 + fraction;
  inflated.skirt_flare_m *= 1.0 + fraction;
  return inflated;
}

constexpr const char* kRepeatedFrameFlag = "duplicate";

// The joints of every limb that `flags` say was re-placed ("limb:NAME", "landmarks:NAME", "twist:NAME").
std::vector<int> ReplacedLimbJoints(const std::vector<std::string>& flags) {
  std::vector<int> joints;
  for (Limb limb : kAllLimbs) {
    const std::string name = LimbName(limb);
    for (const std::string& flag : flags)
      if (flag == kLimbSearchFlag + name || flag == kLandmarksFlag + name || flag == kArmTwistFlag + name) {
        const LimbChain chain = LimbJoints(limb);
        joints.insert(joints.end(), {chain.root, chain.middle, chain.end});
        break;
      }
  }
  return joints;
}

std::size_t HashMask(const Image& mask) {
  return std::hash<std::string_view>()(std::string_view(reinterpret_cast<const char*>(mask.data.data()), mask.data.size()));
}

}  // namespace

SilhouetteFitOptions TrackerOptions::InitialShapeFit(const SilhouetteFitOptions& base) const {
  SilhouetteFitOptions options = base;
  options.fit_shape = true;
  options.rounds = init_rounds;
  options.max_iterations = init_max_iterations;
  options.prior_weight = 0.2;
  options.shape_prior_weight = init_shape_prior_weight;
  options.shape_proportion_weight = init_shape_proportion_weight;
  return options;
}

void TrackerOptions::Check() const {
  fit.Check();
  const std::string owner = "TrackerOptions.";
  RequireOption(init_width >= 16, owner + "init_width", init_width, ">= 16");
  RequireOption(init_rounds >= 1, owner + "init_rounds", init_rounds, ">= 1");
  RequireOption(init_max_iterations >= 1, owner + "init_max_iterations", init_max_iterations, ">= 1");
  RequireOption(skirt_min_iou_gain >= 0 && skirt_min_iou_gain < 1, owner + "skirt_min_iou_gain", skirt_min_iou_gain,
                "in [0, 1)");
  RequireOption(init_rest_pull_min_iou_gain >= 0 && init_rest_pull_min_iou_gain < 1,
                owner + "init_rest_pull_min_iou_gain", init_rest_pull_min_iou_gain, "in [0, 1)");
  RequireOption(shape_samples >= 0, owner + "shape_samples", shape_samples, ">= 0");
  RequireOption(shape_sample_every >= 1, owner + "shape_sample_every", shape_sample_every, ">= 1");
  RequireOption(skirt_try_below_iou >= 0 && skirt_try_below_iou <= 1, owner + "skirt_try_below_iou",
                skirt_try_below_iou, "in [0, 1]");
  skirt_search.Check(owner + "skirt_search.");
  RequireOption(girth_inflation_max >= 0 && girth_inflation_max <= 0.5, owner + "girth_inflation_max",
                girth_inflation_max, "in [0, 0.5]");
  RequireOption(girth_inflation_below_iou >= 0 && girth_inflation_below_iou <= 1, owner + "girth_inflation_below_iou",
                girth_inflation_below_iou, "in [0, 1]");
  RequireOption(girth_inflation_step > 0 && girth_inflation_step <= 0.5, owner + "girth_inflation_step",
                girth_inflation_step, "in (0, 0.5]");
  RequireOption(girth_inflation_min_gain >= 0, owner + "girth_inflation_min_gain", girth_inflation_min_gain, ">= 0");
  RequireOption(velocity_damping >= 0 && velocity_damping <= 1.5, owner + "velocity_damping", velocity_damping,
                "in [0, 1.5]");
  RequireOption(bad_frame_iou >= 0 && bad_frame_iou <= 1, owner + "bad_frame_iou", bad_frame_iou, "in [0, 1]");
  RequireOption(empty_mask_fraction >= 0 && empty_mask_fraction < 1, owner + "empty_mask_fraction",
                empty_mask_fraction, "in [0, 1)");
  RequireOption(iou_downscale >= 0, owner + "iou_downscale", iou_downscale, ">= 0");
  RequireOption(limb_search_drop >= 0 && limb_search_drop < 1, owner + "limb_search_drop", limb_search_drop,
                "in [0, 1)");
  RequireOption(limb_search_contour_rise == 0 || limb_search_contour_rise > 1, owner + "limb_search_contour_rise",
                limb_search_contour_rise, "0 or > 1");
  RequireOption(limb_search_repeat_drop >= 0 && limb_search_repeat_drop < 1, owner + "limb_search_repeat_drop",
                limb_search_repeat_drop, "in [0, 1)");
  RequireOption(limb_search_repeat_rise >= 1, owner + "limb_search_repeat_rise", limb_search_repeat_rise, ">= 1");
  RequireOption(limb_fits >= 1 && limb_fits <= 16, owner + "limb_fits", limb_fits, "in [1, 16]");
  RequireOption(limb_fits_init >= 1 && limb_fits_init <= 16, owner + "limb_fits_init", limb_fits_init, "in [1, 16]");
  RequireOption(init_shape_prior_weight >= 0, owner + "init_shape_prior_weight", init_shape_prior_weight, ">= 0");
  RequireOption(init_shape_proportion_weight >= 0, owner + "init_shape_proportion_weight",
                init_shape_proportion_weight, ">= 0");
  RequireOption(limb_min_gain >= 0 && limb_min_gain < 1, owner + "limb_min_gain", limb_min_gain, "in [0, 1)");
  RequireOption(landmark_check_every >= 0, owner + "landmark_check_every", landmark_check_every, ">= 0");
  RequireOption(arm_twist_every >= 0, owner + "arm_twist_every", arm_twist_every, ">= 0");
  RequireOption(arm_twist_max_elbow_rad >= 0, owner + "arm_twist_max_elbow_rad", arm_twist_max_elbow_rad, ">= 0");
  RequireOption(arm_twist_bend_rad >= 0, owner + "arm_twist_bend_rad", arm_twist_bend_rad, ">= 0");
  RequireOption(arm_twist_min_gain >= 0, owner + "arm_twist_min_gain", arm_twist_min_gain, ">= 0");
  RequireOption(landmark_disagreement_m > 0, owner + "landmark_disagreement_m", landmark_disagreement_m, "> 0");
  RequireOption(landmark_min_approach_m >= 0, owner + "landmark_min_approach_m", landmark_min_approach_m, ">= 0");
  RequireOption(hand_rebend_min_rad >= 0, owner + "hand_rebend_min_rad", hand_rebend_min_rad, ">= 0");
  for (double flex : hand_rebend_flex_deg)
    RequireOption(std::abs(flex) <= 180, owner + "hand_rebend_flex_deg", flex, "in [-180, 180]");
  RequireOption(landmark_iou_tolerance >= 0 && landmark_iou_tolerance < 1, owner + "landmark_iou_tolerance",
                landmark_iou_tolerance, "in [0, 1)");
  RequireOption(landmark_full_tolerance_m > landmark_disagreement_m, owner + "landmark_full_tolerance_m",
                landmark_full_tolerance_m, "> landmark_disagreement_m");
  RequireOption(landmark_hand_disagreement_rad > 0, owner + "landmark_hand_disagreement_rad",
                landmark_hand_disagreement_rad, "> 0");
  RequireOption(landmark_hand_min_approach_rad >= 0, owner + "landmark_hand_min_approach_rad",
                landmark_hand_min_approach_rad, ">= 0");
  RequireOption(landmark_hand_iou_tolerance >= 0 && landmark_hand_iou_tolerance < 1,
                owner + "landmark_hand_iou_tolerance", landmark_hand_iou_tolerance, "in [0, 1)");
  RequireOption(landmark_hand_max_wrist_gap_m > 0, owner + "landmark_hand_max_wrist_gap_m",
                landmark_hand_max_wrist_gap_m, "> 0");
}

Tracker::Tracker(const Rig& rig, const std::vector<bool>& excluded, const TrackerOptions& options)
    : rig_(rig), excluded_(excluded), options_(options) {
  options_.Check();
  excluded_.resize(rig_.size(), false);
}

std::vector<bool> Tracker::UsableCameras(const std::vector<Image>& masks, std::vector<std::string>* flags) const {
  std::vector<bool> use(rig_.size(), false);
  std::vector<double> counts(rig_.size(), 0.0);
  std::vector<double> candidates;
  for (int c = 0; c < rig_.size(); ++c) {
    if (excluded_[c] || c >= static_cast<int>(masks.size())) continue;
    counts[c] = static_cast<double>(CountForeground(masks[c])) / std::max(1, masks[c].width * masks[c].height);
    candidates.push_back(counts[c]);
  }
  const double median = Median(candidates);
  for (int c = 0; c < rig_.size(); ++c) {
    if (excluded_[c] || c >= static_cast<int>(masks.size())) continue;
    if (masks[c].empty() || counts[c] <= options_.empty_mask_fraction * median || counts[c] <= 0.0) {
      flags->push_back("empty_mask:" + rig_.cameras[c].name);
      continue;
    }
    use[c] = true;
  }
  return use;
}

void Tracker::Evaluate(const BodyShape& shape, const std::vector<Image>& masks, const std::vector<bool>& use,
                       TrackedFrame* result) const {
  result->camera_iou = SilhouetteIoUs(body_.PosedMesh(shape, result->pose), rig_, masks, use, options_.iou_downscale);
  result->mean_iou = MeanSilhouetteIoU(result->camera_iou);
  result->joints = body_.JointPositions(shape, result->pose);
}

void Tracker::SearchSkirtShape(const std::vector<Image>& masks, const std::vector<bool>& use,
                               const SilhouetteObservations& observations, TrackedFrame* result) {
  if (!options_.skirt_search.enabled || shape_.skirt_length_m <= 0.0) return;
  const SkirtSearchResult found = SearchSkirt(shape_, options_.skirt_search, [&](const BodyShape& shape) {
    TrackedFrame candidate = *result;
    Evaluate(shape, masks, use, &candidate);
    return candidate.mean_iou;
  });
  if (!found.changed) return;
  shape_ = found.shape;
  Evaluate(shape_, masks, use, result);
  // The pose was fitted inside the other skirt: fitted again inside this one, kept when better.
  TrackedFrame refit = *result;
  refit.fit = FitTemplateToSilhouettes(body_, observations, options_.fit, &shape_, &refit.pose);
  Evaluate(shape_, masks, use, &refit);
  if (refit.mean_iou > result->mean_iou) *result = std::move(refit);
  const auto cm = [](double m) { return std::to_string(static_cast<int>(std::lround(100 * m))); };
  result->flags.push_back("skirt:" + cm(shape_.skirt_length_m) + "cm+" + cm(shape_.skirt_flare_m) + "cm");
}

SilhouetteObservations Tracker::Observations(const std::vector<Image>& masks, const std::vector<bool>& use) const {
  return SilhouetteObservations(rig_, masks, use, options_.fit.downscale, options_.fit.max_contour_points,
                                options_.fit.automatic_width);
}

bool Tracker::InitScaleIsTrackingScale(const std::vector<Image>& masks, const std::vector<bool>& use) const {
  for (int c = 0; c < rig_.size(); ++c)
    if (use[c] && FitReductionFactor(options_.fit.downscale, masks[c].width, options_.init_width) !=
                      FitReductionFactor(options_.fit.downscale, masks[c].width, options_.fit.automatic_width))
      return false;
  return true;
}

void Tracker::RefitFirstFrame(const std::vector<Image>& masks, const std::vector<bool>& use,
                              const SilhouetteObservations& observations, TrackedFrame* result) {
  SilhouetteFitOptions refit = options_.fit;
  refit.rest_prior_scale = init_rest_prior_scale_;
  const TemplatePose first_pose = result->pose;
  result->fit = FitTemplateToSilhouettes(body_, observations, refit, &shape_, &result->pose, &first_pose);
  Evaluate(shape_, masks, use, result);
  RestartHistoryAt(*result);
}

void Tracker::RestartHistoryAt(const TrackedFrame& frame) {
  history_ = {frame.pose};
  iou_history_ = {frame.mean_iou};
  contour_history_ = {frame.fit.mean_contour_px};
}

void Tracker::InflateGirths(const std::vector<Image>& masks, const std::vector<bool>& use, TrackedFrame* result) {
  if (options_.girth_inflation_max <= 0.0 || result->mean_iou >= options_.girth_inflation_below_iou) return;
  TrackedFrame best = *result;
  double best_fraction = 0.0;
  const int steps = static_cast<int>(std::floor(options_.girth_inflation_max / options_.girth_inflation_step + 1e-9));
  for (int k = 1; k <= steps; ++k) {
    const double fraction = k * options_.girth_inflation_step;
    TrackedFrame candidate = *result;
    Evaluate(InflatedGirths(shape_, fraction), masks, use, &candidate);
    if (candidate.mean_iou > best.mean_iou) {
      best = std::move(candidate);
      best_fraction = fraction;
    }
  }
  if (best_fraction == 0.0 || best.mean_iou < result->mean_iou + options_.girth_inflation_min_gain) return;
  shape_ = InflatedGirths(shape_, best_fraction);
  best.flags.push_back("girths:+" + std::to_string(static_cast<int>(std::lround(100 * best_fraction))) + "%");
  *result = std::move(best);
}

// The first frame's shape and pose from `start_shape` (hypotheses of facing and arms, then a joint
// shape-and-pose fit), with the pulls towards rest angles scaled by `rest_prior_scale`.
TrackedFrame Tracker::FitFirstFrame(int frame, const std::vector<Image>& masks, const std::vector<bool>& use,
                                    const SilhouetteObservations& observations, const BodyShape& start_shape,
                                    double rest_prior_scale, BodyShape* fitted_shape) const {
  SilhouetteFitOptions init_fit = options_.fit;
  init_fit.rest_prior_scale = rest_prior_scale;
  init_fit.max_wrist_palm_bend_rad = options_.first_frame_wrist_palm_bend_rad;
  SilhouetteFitOptions hypothesis_options = init_fit;
  hypothesis_options.prior_weight = 0.2;
  hypothesis_options.rounds = 2;
  hypothesis_options.max_iterations = 20;
  TrackedFrame best;
  best.mean_iou = -1.0;
  for (double yaw_offset : {0.0, M_PI}) {
    for (double arm_deg : {0.0, 45.0, -30.0}) {
      TrackedFrame candidate;
      candidate.frame = frame;
      TemplatePose& pose = candidate.pose;
      pose.root_translation = Vector3d(placement_.centroid.x(), placement_.centroid.y(), placement_.floor_z);
      pose.root_rotation = Vector3d(0, 0, placement_.yaw_rad + yaw_offset);
      const double arm = arm_deg * M_PI / 180.0;
      pose.dofs[kJointLeftShoulder] = {0.0, arm, 0.0};
      pose.dofs[kJointRightShoulder] = {0.0, -arm, 0.0};
      BodyShape shape = start_shape;
      candidate.fit = FitTemplateToSilhouettes(body_, observations, hypothesis_options, &shape, &pose);
      Evaluate(start_shape, masks, use, &candidate);
      if (candidate.mean_iou > best.mean_iou) best = candidate;
    }
  }
  // Joint shape-and-pose fit from the best hypothesis, then a final pose refinement.
  const SilhouetteFitOptions shape_options = options_.InitialShapeFit(init_fit);
  SilhouetteFitOptions refine = init_fit;
  refine.prior_weight = 0.2;
  refine.rounds = 2;
  refine.coarse_to_fine = false;
  // Two hypotheses: no skirt (the DOF held at zero), and a skirt fitted from a long start (the
  // shape fit alone does not find a skirt from none), tried only when the first leaves the
  // silhouettes poorly explained. The skirt wins only when its overlap is clearly better.
  TrackedFrame result;
  result.mean_iou = -1.0;
  for (int skirt_start = 0; skirt_start < (options_.try_skirt ? 2 : 1); ++skirt_start) {
    if (skirt_start == 1 && result.mean_iou >= options_.skirt_try_below_iou) break;
    TrackedFrame candidate;
    candidate.frame = frame;
    BodyShape shape = start_shape;
    if (skirt_start == 1) {
      shape.skirt_length_m = 0.5 * shape.length_scale[0];
      shape.skirt_flare_m = 0.1 * shape.girth_scale[0];
    }
    TemplatePose pose = best.pose;
    SilhouetteFitOptions candidate_options = shape_options;
    candidate_options.fit_skirt = skirt_start == 1;
    SilhouetteFitSummary summary = FitTemplateToSilhouettes(body_, observations, candidate_options, &shape, &pose);
    const SilhouetteFitSummary refined = FitTemplateToSilhouettes(body_, observations, refine, &shape, &pose);
    summary.iterations += refined.iterations;
    summary.final_cost = refined.final_cost;
    summary.mean_outside_px = refined.mean_outside_px;
    summary.mean_contour_px = refined.mean_contour_px;
    candidate.pose = pose;
    candidate.fit = summary;
    Evaluate(shape, masks, use, &candidate);
    if (candidate.mean_iou > result.mean_iou + (skirt_start == 1 ? options_.skirt_min_iou_gain : 0.0)) {
      result = candidate;
      *fitted_shape = shape;
    }
  }
  return result;
}

TrackedFrame Tracker::Initialize(int frame, const std::vector<Image>& masks) {
  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();
  TrackedFrame result;
  result.frame = frame;
  const std::vector<bool> use = UsableCameras(masks, &result.flags);
  initialized_ = false;
  placement_ = EstimatePlacementFromHull(rig_, masks, use);
  history_.clear();
  iou_history_.clear();
  contour_history_.clear();
  replaced_joints_.clear();
  last_mask_hashes_.clear();
  fruitless_search_ = {};
  if (!placement_.ok) {
    result.flags.push_back("no_hull");
    return result;
  }
  const SilhouetteObservations observations(rig_, masks, use, options_.fit.downscale, options_.fit.max_contour_points,
                                            options_.init_width);
  // Without and with the wrists' pull towards straight hands (JointDof::rest_weight): a boxer's
  // guard comes out with arms 10% short without it (Bandai's kick and punch), a hand bent across
  // the forearm turns the forearm with it (the Indian dance: wrists 12 cm off).
  // The two fits are independent: with two or more solver threads the second runs beside the
  // first (the same poses; the first frame 14-15% sooner on two cores, bench/RESULTS.md), else after it.
  const BodyShape start_shape = BodyShape::Uniform(std::clamp(placement_.height_m, 1.0, 2.3));
  BodyShape fitted_shape = start_shape, pulled_shape = start_shape;
  TrackedFrame fitted, pulled;
  const bool try_pull = options_.fit.rest_prior_scale > 0.0;
  ParallelFor(try_pull ? 2 : 1, options_.fit.num_threads >= 2 ? 2 : 1, [&](int fit) {
    if (fit == 0)
      fitted = FitFirstFrame(frame, masks, use, observations, start_shape, 0.0, &fitted_shape);
    else
      pulled = FitFirstFrame(frame, masks, use, observations, start_shape, options_.fit.rest_prior_scale,
                             &pulled_shape);
  });
  init_rest_prior_scale_ = 0.0;
  if (try_pull && pulled.mean_iou > fitted.mean_iou + options_.init_rest_pull_min_iou_gain) {
    fitted = std::move(pulled);
    fitted_shape = pulled_shape;
    init_rest_prior_scale_ = options_.fit.rest_prior_scale;
    result.flags.push_back("wrists_pulled");
  }
  fitted.flags.insert(fitted.flags.begin(), result.flags.begin(), result.flags.end());
  result = std::move(fitted);
  shape_ = fitted_shape;  // FitFirstFrame evaluated `result` with it
  SearchSkirtShape(masks, use, observations, &result);
  if (options_.limb_search) SearchLimbs(masks, use, observations, options_.limb_fits_init, &result);
  SettleLimbsByLandmarks(masks, use, observations, &result);
  SearchArmTwists(masks, use, observations, 3, &result);
  InflateGirths(masks, use, &result);
  result.flags.push_back("initialized");
  initialized_ = true;
  RestartHistoryAt(result);
  for (const Image& m : masks) last_mask_hashes_.push_back(HashMask(m));
  // Fitted at a coarser scale than the frames after it: fitted again at theirs.
  std::optional<SilhouetteObservations> finer;
  if (!InitScaleIsTrackingScale(masks, use)) {
    finer = Observations(masks, use);
    RefitFirstFrame(masks, use, *finer, &result);
  }
  LearnShapeOverFirstFrames(masks, use, finer ? *finer : observations, &result);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.cpu_seconds = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  return result;
}

void Tracker::Resume(const BodyShape& shape, const std::vector<TemplatePose>& recent_poses,
                     const std::vector<double>& recent_ious, const std::vector<double>& recent_contour_px) {
  if (recent_poses.empty()) throw std::invalid_argument("Tracker::Resume: no previous pose");
  shape_ = shape;
  history_.assign(recent_poses.end() - std::min<std::size_t>(recent_poses.size(), 4), recent_poses.end());
  iou_history_ = recent_ious;
  contour_history_ = recent_contour_px;
  replaced_joints_.clear();
  last_mask_hashes_.clear();
  fruitless_search_ = {};
  initialized_ = true;
}

bool IsRepeatedFrame(const TrackedFrame& frame) {
  return std::find(frame.flags.begin(), frame.flags.end(), kRepeatedFrameFlag) != frame.flags.end();
}

void Tracker::ResumeAfter(const BodyShape& shape, const std::vector<TrackedFrame>& before,
                          const std::vector<Image>& last_masks) {
  std::vector<TemplatePose> poses;
  std::vector<double> ious, contours;
  const TrackedFrame* last = nullptr;
  for (const TrackedFrame& f : before) {
    if (IsRepeatedFrame(f)) continue;
    poses.push_back(f.pose);
    AppendToWindow(&ious, f.mean_iou, kIouWindow);
    AppendToWindow(&contours, f.fit.mean_contour_px, kIouWindow);
    last = &f;
  }
  if (poses.empty()) throw std::invalid_argument("Tracker::ResumeAfter: no tracked frame before");
  Resume(shape, poses, ious, contours);
  replaced_joints_ = ReplacedLimbJoints(last->flags);
  fruitless_search_ = last->fruitless_search;
  for (const Image& m : last_masks) last_mask_hashes_.push_back(HashMask(m));
}

TrackedFrame Tracker::Track(int frame, const std::vector<Image>& masks) {
  if (!initialized_) return Initialize(frame, masks);
  const auto start = std::chrono::steady_clock::now();
  const std::clock_t cpu_start = std::clock();
  TrackedFrame result;
  result.frame = frame;
  const std::vector<bool> use = UsableCameras(masks, &result.flags);
  // A repeated frame (identical masks): keep the pose, do not disturb the velocity.
  std::vector<std::size_t> hashes;
  for (const Image& m : masks) hashes.push_back(HashMask(m));
  if (hashes == last_mask_hashes_) {
    result.pose = history_.back();
    result.flags.push_back(kRepeatedFrameFlag);
    Evaluate(shape_, masks, use, &result);
    result.fruitless_search = fruitless_search_;
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.cpu_seconds = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    return result;
  }
  last_mask_hashes_ = hashes;
  // Constant-velocity prediction.
  const TemplatePose& last = history_.back();
  TemplatePose predicted = last;
  if (history_.size() >= 2) {
    const TemplatePose& before = history_[history_.size() - 2];
    const double k = options_.velocity_damping;
    predicted.root_translation = last.root_translation + k * (last.root_translation - before.root_translation);
    const Matrix3d R1 = RotationOf(last.root_rotation), R0 = RotationOf(before.root_rotation);
    predicted.root_rotation = RotationVector(RotationOf(k * RotationVector(R1 * R0.transpose())) * R1);
    for (int j = 0; j < kNumTemplateJoints; ++j)
      for (int d = 0; d < 3; ++d) predicted.dofs[j][d] = last.dofs[j][d] + k * (last.dofs[j][d] - before.dofs[j][d]);
    for (int j : replaced_joints_) predicted.dofs[j] = last.dofs[j];
    if (!options_.extrapolate_wrists)
      for (int j : {kJointLeftWrist, kJointRightWrist}) predicted.dofs[j] = last.dofs[j];
    body_.ClampToLimits(&predicted);
  }
  const SilhouetteObservations observations = Observations(masks, use);
  result.pose = predicted;
  result.fit = FitTemplateToSilhouettes(body_, observations, options_.fit, &shape_, &result.pose, &predicted);
  Evaluate(shape_, masks, use, &result);
  // Bad-frame detection and recovery: re-fit from the neighbouring accepted poses.
  std::vector<double> recent(iou_history_.end() - std::min<std::size_t>(iou_history_.size(), 10), iou_history_.end());
  const double reference = Median(recent);
  const bool bad = result.mean_iou < options_.bad_frame_iou || result.mean_iou < reference - options_.bad_frame_iou_drop;
  if (bad) {
    SilhouetteFitOptions recover = options_.fit;
    recover.rounds = options_.fit.rounds + 1;
    recover.max_iterations = 2 * options_.fit.max_iterations;
    recover.prior_weight = 0.5 * options_.fit.prior_weight;
    const double before_iou = result.mean_iou;
    for (std::size_t back = 1; back <= std::min<std::size_t>(2, history_.size()); ++back) {
      TrackedFrame candidate;
      candidate.frame = frame;
      candidate.pose = history_[history_.size() - back];
      const TemplatePose start_pose = candidate.pose;
      candidate.fit = FitTemplateToSilhouettes(body_, observations, recover, &shape_, &candidate.pose, &start_pose);
      Evaluate(shape_, masks, use, &candidate);
      if (candidate.mean_iou > result.mean_iou) {
        candidate.flags = result.flags;
        result = candidate;
      }
    }
    result.flags.push_back(result.mean_iou > before_iou ? "recovered" : "bad");
    if (result.mean_iou < options_.bad_frame_iou) result.flags.push_back("low_overlap");
  }
  // A lost limb: the overlap falls below what this performance has shown lately.
  const std::vector<double> window(iou_history_.end() - std::min<std::size_t>(iou_history_.size(), kIouWindow),
                                   iou_history_.end());
  // ... or the contours are explained much worse than lately: a forearm held inside the torso's
  // silhouette in the front cameras costs little overlap, but its true outline in the others goes
  // unexplained.
  const bool contour_rise = options_.limb_search_contour_rise > 0 && contour_history_.size() >= 3 &&
                            result.fit.mean_contour_px > options_.limb_search_contour_rise * Median(contour_history_);
  const bool triggered =
      options_.limb_search && (contour_rise || result.mean_iou < Median(window) - options_.limb_search_drop);
  const bool no_worse_than_fruitless =
      fruitless_search_.pending() &&
      result.mean_iou >= fruitless_search_.mean_iou - options_.limb_search_repeat_drop &&
      result.fit.mean_contour_px <= options_.limb_search_repeat_rise * fruitless_search_.mean_contour_px;
  if (triggered && !no_worse_than_fruitless) {
    const std::size_t flags_before = result.flags.size();
    const FruitlessLimbSearch searched_at{result.mean_iou, result.fit.mean_contour_px};
    SearchLimbs(masks, use, observations, options_.limb_fits, &result);
    SettleLimbsByLandmarks(masks, use, observations, &result);
    result.limb_search = LimbSearch::kRan;
    fruitless_search_ = result.flags.size() == flags_before ? searched_at : FruitlessLimbSearch{};
  } else {
    if (triggered) result.limb_search = LimbSearch::kSkipped;
    else fruitless_search_ = {};
    if (options_.landmark_check_every > 0 && frame % options_.landmark_check_every == 0)
      SettleLimbsByLandmarks(masks, use, observations, &result);
  }
  if (options_.arm_twist_every > 0 && frame % options_.arm_twist_every == 0)
    SearchArmTwists(masks, use, observations, 1, &result);
  result.fruitless_search = fruitless_search_;
  history_.push_back(result.pose);
  if (history_.size() > 4) history_.erase(history_.begin());
  replaced_joints_ = ReplacedLimbJoints(result.flags);
  // The accepted frame's overlap and residual, as its state file records them (Resume).
  AppendToWindow(&iou_history_, result.mean_iou, kIouWindow);
  AppendToWindow(&contour_history_, result.fit.mean_contour_px, kIouWindow);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.cpu_seconds = static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  return result;
}

}  // namespace confluent
