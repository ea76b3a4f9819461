#pragma once
// Fitting the body template's pose (and optionally its shape) to the silhouettes of several
// calibrated cameras with Ceres (autodiff), after Carranza et al. 2003, in a formulation with
// distance transforms:
//  - model -> image: surface samples of every segment, projected, should fall inside the
//    silhouette (signed distance transform of the mask, bicubic interpolation, Huber loss);
//  - image -> model: contour pixels of the silhouette should be explained by the model: the
//    normalised distance from the pixel's back-projected ray to its nearest segment capsule
//    (nearest segment re-assigned every round, Cauchy loss);
//  - a weak prior towards the predicted pose; joint limits as parameter bounds;
//  - coarse to fine: root and torso first, then every joint.

#include <memory>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "tracking/body_template.h"

namespace confluent {

// The width masks are reduced to for fitting when no factor is given (SilhouetteFitOptions).
constexpr int kDefaultFitWidth = 256;

// Options of FitTemplateToSilhouettes.
struct SilhouetteFitOptions {
  int downscale = 0;               // masks are reduced by this factor before the distance transforms;
                                   // 0 = automatic (about automatic_width pixels across)
  int automatic_width = kDefaultFitWidth;
  int max_contour_points = 250;    // contour pixels per camera for the image -> model term
  int rounds = 2;                  // contour re-assignment rounds of the full-body stage
  int max_iterations = 12;         // Levenberg-Marquardt iterations per round
  bool coarse_to_fine = true;      // fit root and torso first (one round), then everything
  bool fit_shape = false;          // also optimise the per-segment length and girth scales
  bool fit_pose = true;            // optimise the pose (false: only the shape)
  double model_to_image_loss_px = 2.0;  // Huber scale of the model -> image residuals (reduced px)
  double image_to_model_loss_px = 3.0;  // Cauchy scale of the image -> model residuals (reduced px)
  double image_to_model_weight = 1.5;   // relative weight of the image -> model term
  double prior_weight = 2.0;       // weight (per radian) of the prior towards the initial joint angles
  double rest_prior_scale = 1.0;   // scale of the template's pulls towards rest angles (JointDof::rest_weight)
  // >= 0: the wrists' out-of-plane bend (towards the palm or its back) kept within this angle,
  // inside the template's range (the first frame's fits start far from the pose, where a wide
  // range folds a forearm back or bends a boxer's fists); < 0: the template's range.
  double max_wrist_palm_bend_rad = -1.0;
  double shape_prior_weight = 20.0;     // weight of the prior towards the start's mean scale (uniform body)
  // Weight of the prior towards equal proportions: each group's scale towards the mean of the
  // current lengths (or girths), whatever the overall size. With a weak shape_prior_weight the
  // body may grow or shrink as a whole (a crouched first frame under-estimates the height)
  // while keeping human proportions.
  double shape_proportion_weight = 0.0;
  bool fit_skirt = true;           // with fit_shape: also optimise BodyShape's skirt length and flare
  double skirt_prior_weight = 2.0; // weight (per metre) of the prior towards no skirt
  // With fit_shape: also optimise the cross-sections (BodyShape::depth_scale, taper_scale,
  // depth_offset and mid_bulge per group), pulled towards the generic template's (1, 1, 0, 0) with
  // this weight, scales within [min_section_scale, max_section_scale], offsets within
  // +-max_depth_offset, bulges within +-max_mid_bulge.
  bool fit_sections = true;
  double section_prior_weight = 20.0;
  double min_section_scale = 0.7;
  double max_section_scale = 1.5;
  double max_depth_offset = 0.4;
  // Weight of the pull of the torso's depth offsets towards 0 (replaces section_prior_weight for
  // them): an offset moves the bone inside an unchanged outline, so only the joints it connects
  // (hips, shoulders) see it, and a bent torso trades it for the pelvis's pitch.
  double depth_offset_prior_weight = 100.0;
  double max_mid_bulge = 0.3;
  int num_threads = 2;
  // Throws UsageError for out-of-range values.
  void Check() const;
};

// What a fit did.
struct SilhouetteFitSummary {
  bool converged = false;
  int iterations = 0;              // LM iterations over all stages
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double mean_outside_px = 0.0;    // mean distance of model samples outside the silhouettes (reduced px)
  double mean_contour_px = 0.0;    // mean image -> model residual (reduced px)
  int num_cameras = 0;             // cameras used
  double seconds = 0.0;
};

// The factor a mask `mask_width` pixels wide is reduced by: `downscale`, or when 0 the one that
// brings it to about `automatic_width` pixels across (at least 1).
int FitReductionFactor(int downscale, int mask_width, int automatic_width);

// One frame's observations prepared for fitting (distance transforms, contour rays).
class SilhouetteObservations {
 public:
  // Prepares the masks (1-channel 8-bit, 0/255, camera size) of the cameras with
  // `use_camera[i]` (all when empty); masks of unused cameras may be empty images.
  // `downscale` as SilhouetteFitOptions::downscale (0: about `automatic_width` pixels across).
  SilhouetteObservations(const Rig& rig, const std::vector<Image>& masks, const std::vector<bool>& use_camera,
                         int downscale, int max_contour_points, int automatic_width = kDefaultFitWidth);
  ~SilhouetteObservations();
  SilhouetteObservations(SilhouetteObservations&&) noexcept;
  SilhouetteObservations& operator=(SilhouetteObservations&&) noexcept;

  int num_used_cameras() const;
  struct Impl;
  const Impl& impl() const { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

// Fits `pose` (and `shape` when options.fit_shape) to the observations, starting from the
// values passed in. `prior` (may be null) is the pose the joint-angle prior pulls towards
// (usually the prediction). Expected failures are reported in the summary, not thrown.
SilhouetteFitSummary FitTemplateToSilhouettes(const BodyTemplate& body, const SilhouetteObservations& observations,
                                              const SilhouetteFitOptions& options, BodyShape* shape,
                                              TemplatePose* pose, const TemplatePose* prior = nullptr);

}  // namespace confluent
