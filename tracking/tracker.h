#pragma once
// Marker-less motion capture: automatic initialisation of the body template from the visual
// hull and a joint shape-and-pose fit, then frame-by-frame silhouette tracking with constant
// velocity prediction, bad-frame detection and recovery (after Carranza et al. 2003).

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "tracking/body_template.h"
#include "tracking/hull_placement.h"
#include "tracking/landmark_joints.h"
#include "tracking/limb_hypotheses.h"
#include "tracking/silhouette_fit.h"
#include "tracking/skirt_search.h"

namespace confluent {

// Options of the Tracker.
struct TrackerOptions {
  TrackerOptions() { fit.automatic_width = 512; }
  // The per-frame fit, on masks about 512 pixels across (fit.automatic_width) unless
  // fit.downscale fixes the factor: at 256 a foot of a 1024x768 camera is 5 pixels long, and
  // Perfume's dancer stood with both legs turned 18-21 degrees about their axes, unseen.
  SilhouetteFitOptions fit;
  // The first frame's fits (Initialize) run on masks about this many pixels across when
  // fit.downscale is automatic (0), then the first frame is fitted again at the per-frame scale.
  // From the visual hull's rough placement the finer distance transforms give a narrower basin:
  // at 512 the pirouette's first frame stopped at a tracking IoU of 0.813 (0.926 at 256).
  int init_width = 256;
  int init_rounds = 3;             // contour rounds of the initial shape-and-pose fit ...
  // ... and Levenberg-Marquardt iterations per round (at 25 a crouched first frame's first round
  // stopped early and the next rounds' contours settled on thighs 20% short)
  int init_max_iterations = 40;
  // Shape priors of the initial fit (SilhouetteFitOptions): a weak pull towards the hull's
  // height (a crouched first frame under-estimates it) and a strong one towards human
  // proportions (at 40, arms hanging against the thighs came out 10-18% short: the modern dance's
  // wrists 7.8 cm off at every frame; 100 gives 4.7 cm at the 95th percentile).
  double init_shape_prior_weight = 2.0;
  double init_shape_proportion_weight = 100.0;
  bool try_skirt = true;           // initial shape fit also from a long skirt (BodyShape::skirt_*) ...
  double skirt_try_below_iou = 0.92; // ... when the fit without one has a mean IoU below this (1: always) ...
  double skirt_min_iou_gain = 0.01; // ... kept when its mean IoU beats the fit without by this much
  // A fitted skirt's length and flare are then searched for the best overlap of the tracking
  // cameras (the fit makes a dress that flares on some sides a long straight tube).
  SkirtSearchOptions skirt_search;
  // The first frame is fitted without and with the pulls towards rest angles (fit.rest_prior_scale);
  // the pulled fit is kept when its mean IoU beats the other by this much.
  double init_rest_pull_min_iou_gain = 0.002;
  // After the initial fit, every girth (and the skirt's flare) is tried grown by up to this
  // fraction in steps of girth_inflation_step, kept at the step that overlaps the tracking cameras
  // best when that beats the fit by girth_inflation_min_gain (0: never). The fit keeps the
  // template inside the silhouettes, so loose clothes and cameras that disagree by a few pixels
  // leave it thin (the Tsinghua dancer: 3-4 px inside the masks all round). Tried only when the
  // fit leaves the tracking cameras' mean IoU below girth_inflation_below_iou (1: always): grown
  // capsules poke out of every later frame's silhouettes, which costs a well-fitted capture's scan.
  double girth_inflation_max = 0.1;
  double girth_inflation_below_iou = 0.91;
  double girth_inflation_step = 0.02;
  double girth_inflation_min_gain = 0.003;
  double velocity_damping = 0.7;   // fraction of the last frame's velocity used for the prediction
  // The wrists are predicted where they are, without the velocity: a hand is a few pixels wide,
  // so its frame-to-frame change is mostly the fit's noise, and extrapolated it becomes a drift
  // the silhouettes do not resist (a still hand flexed 50 degrees over 16 frames).
  bool extrapolate_wrists = false;
  double bad_frame_iou = 0.7;      // mean IoU below this triggers a recovery
  double bad_frame_iou_drop = 0.1; // ... or a drop of this much below the running median
  double empty_mask_fraction = 0.2;  // a camera with less foreground than this fraction of the median camera is skipped
  int iou_downscale = 0;           // resolution reduction of the per-frame IoU check (0 = automatic)
  // Lost limbs: at initialisation, and when a frame's mean IoU falls `limb_search_drop` below
  // the median of the last Tracker::kIouWindow frames, each limb is tried in its canonical placements
  // (tracking/limb_hypotheses.h), scored unfitted by overlap; the `limb_fits` best are fitted
  // and one is kept when it raises the frame's mean IoU by `limb_min_gain`.
  bool limb_search = true;
  double limb_search_drop = 0.02;
  // ... and when the fit's mean contour residual (SilhouetteFitSummary::mean_contour_px) exceeds
  // this multiple of its median over the last kIouWindow frames (0: never).
  double limb_search_contour_rise = 1.3;
  // A search that keeps the pose is not run again on the frames after it while they are no worse
  // than the frame it ran on: until a frame's mean IoU is `limb_search_repeat_drop` lower or its
  // contour residual `limb_search_repeat_rise` times higher (or a frame no longer triggers it). A
  // slow decline (the demo's arms rising: 0.945 -> 0.907 over 9 frames) lags the medians, and
  // the search ran on 18 frames there, 80 s of CPU, and kept the pose on every one.
  double limb_search_repeat_drop = 0.01;
  double limb_search_repeat_rise = 1.15;
  int limb_fits = 2;
  int limb_fits_init = 4;          // at initialisation (once per run), more of them are fitted
  double limb_min_gain = 0.005;
  // Landmarks (Tracker::UseLandmarks): a limb whose wrist or ankle lies `landmark_disagreement_m`
  // or more from them is turned towards them (tracking/landmark_limbs.h) and fitted again, and
  // kept when its end comes `landmark_min_approach_m` closer and the mean IoU falls by no more
  // than `landmark_iou_tolerance` (silhouettes hardly tell a forearm folded forward from one
  // folded back; the landmarks do), or when it comes any closer and raises the mean IoU by
  // `limb_min_gain` (BlazePose misplaced the Indian dance's wrists, folded before the chest, by
  // 7-10 cm: the fit that found the true wrist came only 2.8 cm closer to theirs, for +0.013 of
  // IoU). A refit that ends where it started is not kept: on the suite, keeping those (a few mm
  // closer) let the heavy body's arms drift (joint error max 3.3 -> 12.2 cm). A leg whose ankle a
  // fitted skirt hides is left to the silhouettes.
  double landmark_disagreement_m = 0.08;
  double landmark_min_approach_m = 0.04;
  double landmark_iou_tolerance = 0.015;
  // The tolerance grows linearly from 0 at `landmark_disagreement_m` to the full one at this
  // distance: BlazePose's wrists lay 9-14 cm inside the forward jumps' arms held in front of the
  // chest, and turning a wrist that was 6 cm off onto them lost 0.006 of IoU (and 10 cm).
  double landmark_full_tolerance_m = 0.16;
  // An arm re-placed (turned onto the landmarks, or to a canonical placement by the lost-limb
  // search) whose hand is bent `hand_rebend_min_rad` or more at the wrist gets the hand, among
  // these bends (degrees of flexion) and the one it had, that overlaps the masks best before the
  // fit (HandBends; empty: the hand it had). The bend was the fit's for the forearm's old place:
  // the Indian dance's hands, bent 67-73 degrees outwards there, pointed out of the silhouettes,
  // and the refit folded the forearm away again. A hand bent less is kept (on the tiny builtin
  // capture, straightening one bent 16 degrees changed nothing at its frame, 0.0002 of IoU, but
  // set the next frames on another course).
  std::vector<double> hand_rebend_flex_deg = {-60.0, -30.0, 0.0, 30.0, 60.0};
  double hand_rebend_min_rad = 45.0 * M_PI / 180.0;
  // Hands: one pointing `landmark_hand_disagreement_rad` or more away from the landmarks' hand
  // (their wrist to their knuckles) is turned at the wrist onto it and fitted again, and kept when
  // it comes `landmark_hand_min_approach_rad` closer and the mean IoU falls by no more than
  // `landmark_hand_iou_tolerance`. Silhouettes hardly see a hand held against the thigh: on
  // Perfume's dance the tracked right hand swung 45 degrees towards the crotch, unflagged.
  double landmark_hand_disagreement_rad = 0.35;
  double landmark_hand_min_approach_rad = 0.2;
  double landmark_hand_iou_tolerance = 0.003;
  // ... only where the landmarks' wrist lies within this distance of the template's (else their
  // hand's direction is not trusted).
  double landmark_hand_max_wrist_gap_m = 0.05;
  // Besides the first frame and the lost-limb search, the landmarks are asked every this many
  // frames (0: never): a limb held wrong where the overlap does not drop (a forearm folded the
  // other way in front of the chest) is found there.
  int landmark_check_every = 5;
  // Arm twist: a nearly straight arm turns about its own axis without changing its silhouette, so
  // the fit keeps whatever twist it has, and when the arm bends, its elbow's hinge lies in the
  // wrong plane and the fit keeps it straight (the pirouette's right arm: 120-175 degrees off its
  // truth in frames 0-15, the wrist 4-8 cm off). At the first frame and every `arm_twist_every`
  // frames, an arm whose elbow is within `arm_twist_max_elbow_rad` of straight is turned about its
  // upper arm by 90, 180 and -90 degrees and bent to `arm_twist_bend_rad` (ArmTwistHypotheses);
  // the first frame fits all three, later frames the one that overlaps best unfitted; a fit is
  // kept when it raises the mean IoU by `arm_twist_min_gain` (flag `twist:<arm>`).
  bool arm_twist_search = true;
  int arm_twist_every = 5;
  double arm_twist_max_elbow_rad = 20.0 * M_PI / 180.0;
  double arm_twist_bend_rad = 30.0 * M_PI / 180.0;
  double arm_twist_min_gain = 0.002;
  // The first frame's fits keep the wrists' out-of-plane bend within this (the template allows
  // 85 degrees, which tracked frames need: hands flat on the floor; from a start far from the
  // pose it folded the Indian dance's forearm back and shortened Bandai's arms: bench/SUITE.md,
  // session 62). Negative: the template's range.
  double first_frame_wrist_palm_bend_rad = 35.0 * M_PI / 180.0;
  // The shape learned over the first frames: the first frame's fit holds the body to human
  // proportions (init_shape_proportion_weight), so a long-haired head, thin shanks or a heavy
  // torso come out as an average body. With later frames' masks (Tracker::UseLaterMasks), the
  // frames after the first are tracked ahead with that shape, the shape and pose are fitted
  // freely (fit's shape priors) on the first frame and every `shape_sample_every`-th one after it,
  // `shape_samples` in all, and their median girths and cross-sections (not lengths: those stay
  // the first fit's) are the tracker's shape from the first frame on (flag "shape:<samples>").
  // 1 or less: the first frame's shape.
  int shape_samples = 6;
  int shape_sample_every = 5;
  // --girth-inflation F: grow the girths by up to F whatever the first frame's overlap (0: never).
  void InflateGirthsAlways(double max_fraction) {
    girth_inflation_max = max_fraction;
    girth_inflation_below_iou = 1.0;
  }
  // The first frame's joint shape-and-pose fit (Tracker::Initialize's), on top of `base`, the
  // options of the first frame's pose fits.
  SilhouetteFitOptions InitialShapeFit(const SilhouetteFitOptions& base) const;
  // Throws UsageError for out-of-range values.
  void Check() const;
};

// The mean IoU that a limb turned onto landmarks `disagreement_m` away from its end may lose and
// still be kept (TrackerOptions::landmark_full_tolerance_m).
double LandmarkIouTolerance(const TrackerOptions& options, double disagreement_m);

// What the lost-limb search did on a frame.
enum class LimbSearch { kNotTriggered, kRan, kSkipped };  // kSkipped: no worse than a fruitless one before

// The frame on which the last lost-limb search kept the pose (TrackerOptions::limb_search_repeat_drop).
struct FruitlessLimbSearch {
  double mean_iou = -1.0;  // < 0: none pending
  double mean_contour_px = 0.0;
  bool pending() const { return mean_iou >= 0.0; }
};

// Result of one frame.
struct TrackedFrame {
  int frame = 0;
  TemplatePose pose;
  std::vector<Eigen::Vector3d> joints;   // world joint positions (template joint order), m
  std::vector<double> camera_iou;        // per rig camera; -1 for cameras not used
  double mean_iou = 0.0;                 // over the used cameras
  SilhouetteFitSummary fit;
  std::vector<std::string> flags;        // "duplicate", "empty_mask:<cam>", "recovered", "bad" ...
  double seconds = 0.0;                  // wall-clock time of the frame
  double cpu_seconds = 0.0;              // process CPU time of the frame (all threads)
  LimbSearch limb_search = LimbSearch::kNotTriggered;
  FruitlessLimbSearch fruitless_search;  // as it stands after this frame (the state a resumed run needs)
};

// Whether `frame` repeated the masks of the one before (flag "duplicate"): Track kept the pose and
// left it out of the history and the lost-limb windows.
bool IsRepeatedFrame(const TrackedFrame& frame);

// Frame-by-frame tracker; holds the shape and the pose history.
class Tracker {
 public:
  // `excluded[i]` marks rig cameras never used (held out); may be empty.
  Tracker(const Rig& rig, const std::vector<bool>& excluded, const TrackerOptions& options = {});

  // Automatic initialisation from one frame's masks (placement from the visual hull, then a
  // joint shape-and-pose fit over several hypotheses of heading and arm pose). Resets history.
  TrackedFrame Initialize(int frame, const std::vector<Image>& masks);
  // Tracks the next frame (Initialize first). Masks: one per rig camera (0/255).
  TrackedFrame Track(int frame, const std::vector<Image>& masks);
  // How many frames back the lost-limb check looks (the median of their mean IoUs): Resume
  // needs the IoUs of this many frames before for a resumed run to track as an uninterrupted one.
  static constexpr int kIouWindow = 25;

  // Joints triangulated from a detector's landmarks in a frame (null: none for that frame).
  using LandmarkSource = std::function<std::shared_ptr<const LandmarkJoints>(int frame)>;
  // Asked at the first frame, in the frames where the lost-limb search runs and every
  // TrackerOptions::landmark_check_every frames: the landmarks settle limbs that the silhouettes
  // leave ambiguous (flag "landmarks:<limb>").
  void UseLandmarks(LandmarkSource source) { landmarks_ = std::move(source); }
  // The masks of a later frame, one per rig camera, for the shape learned over the first frames
  // (TrackerOptions::shape_samples); an empty vector for a frame it does not have.
  using MaskSource = std::function<std::vector<Image>(int frame)>;
  void UseLaterMasks(MaskSource source) { later_masks_ = std::move(source); }

  // Continues from saved state instead of Initialize (a resumed run, or a shard boundary): the
  // fitted shape, the accepted poses of the frames just before (the last 4 are used) and their
  // mean IoUs and mean contour residuals (the last kIouWindow), oldest first.
  void Resume(const BodyShape& shape, const std::vector<TemplatePose>& recent_poses, const std::vector<double>& recent_ious,
              const std::vector<double>& recent_contour_px);
  // The same from the frames tracked before, oldest first, as their state files hold them: a frame
  // flagged "duplicate" is skipped, as Track skipped it, and `last_masks` (the previous frame's;
  // may be empty) let a repeat of them be recognised as in the uninterrupted run. Needs the last
  // kIouWindow frames that are not duplicates (fewer only from the start of the sequence).
  void ResumeAfter(const BodyShape& shape, const std::vector<TrackedFrame>& before, const std::vector<Image>& last_masks);

  bool initialized() const { return initialized_; }
  const BodyTemplate& body() const { return body_; }
  const BodyShape& shape() const { return shape_; }
  const HullPlacement& placement() const { return placement_; }

 private:
  std::vector<bool> UsableCameras(const std::vector<Image>& masks, std::vector<std::string>* flags) const;
  // result->pose's overlap with the masks of the cameras in `use` and its joints, with `shape`.
  void Evaluate(const BodyShape& shape, const std::vector<Image>& masks, const std::vector<bool>& use,
                TrackedFrame* result) const;
  // `hypothesis` fitted to `observations` (pulled towards itself, all segments at once) and scored.
  TrackedFrame FitLimbHypothesis(const TemplatePose& hypothesis, int frame, const std::vector<Image>& masks,
                                 const std::vector<bool>& use, const SilhouetteObservations& observations);
  // The `count` of `hypotheses` (at most) that overlap the masks best as they are, best first.
  std::vector<TemplatePose> BestUnfitted(const std::vector<TemplatePose>& hypotheses, int count,
                                         const std::vector<Image>& masks, const std::vector<bool>& use) const;
  // `pose` with the hand of `arm` re-bent where it overlaps best (TrackerOptions::hand_rebend_flex_deg);
  // `pose` itself for a leg or a hand bent less than hand_rebend_min_rad.
  TemplatePose WithBestHand(const TemplatePose& pose, Limb arm, const std::vector<Image>& masks,
                            const std::vector<bool>& use) const;
  // TrackerOptions::arm_twist_search: `fits` of the hypotheses, the best unfitted first.
  void SearchArmTwists(const std::vector<Image>& masks, const std::vector<bool>& use,
                       const SilhouetteObservations& observations, int fits, TrackedFrame* result);
  // Re-places each limb of `result` (fitted to `observations`) where it overlaps the masks
  // better, flagging "limb:<name>" for each limb moved.
  void SearchLimbs(const std::vector<Image>& masks, const std::vector<bool>& use,
                   const SilhouetteObservations& observations, int fits, TrackedFrame* result);
  // Turns each limb of `result` that disagrees with the landmarks of its frame towards them, then
  // each hand (see TrackerOptions); nothing without a landmark source.
  void SettleLimbsByLandmarks(const std::vector<Image>& masks, const std::vector<bool>& use,
                              const SilhouetteObservations& observations, TrackedFrame* result);
  // Changes a fitted skirt's length and flare where that overlaps the masks better (skirt_search).
  // The pose is then fitted again, kept when it overlaps better.
  void SearchSkirtShape(const std::vector<Image>& masks, const std::vector<bool>& use,
                        const SilhouetteObservations& observations, TrackedFrame* result);
  // TrackerOptions::shape_samples: the first frame's shape and `result` (that frame's fit)
  // replaced by the median of shapes fitted over the first frames, tracked ahead on a copy.
  void LearnShapeOverFirstFrames(const std::vector<Image>& masks, const std::vector<bool>& use,
                                 const SilhouetteObservations& observations, TrackedFrame* result);
  // Grows every girth of the shape where that overlaps the masks better (TrackerOptions::girth_inflation_max).
  void InflateGirths(const std::vector<Image>& masks, const std::vector<bool>& use, TrackedFrame* result);
  // The masks prepared for the per-frame fit (TrackerOptions::fit's scale).
  SilhouetteObservations Observations(const std::vector<Image>& masks, const std::vector<bool>& use) const;
  // Whether Initialize's scale (TrackerOptions::init_width) reduces every used camera's mask as
  // the per-frame fit's does.
  bool InitScaleIsTrackingScale(const std::vector<Image>& masks, const std::vector<bool>& use) const;
  // The first frame's pose fitted again on `observations` (the per-frame scale), the shape kept.
  void RefitFirstFrame(const std::vector<Image>& masks, const std::vector<bool>& use,
                       const SilhouetteObservations& observations, TrackedFrame* result);
  // The accepted poses, overlaps and contour residuals restarted at `frame` alone.
  void RestartHistoryAt(const TrackedFrame& frame);
  // Initialize's fit of the first frame from `start_shape`, with the pulls towards rest angles
  // scaled by `rest_prior_scale`; the shape in `fitted_shape`.
  TrackedFrame FitFirstFrame(int frame, const std::vector<Image>& masks, const std::vector<bool>& use,
                             const SilhouetteObservations& observations, const BodyShape& start_shape,
                             double rest_prior_scale, BodyShape* fitted_shape) const;

  Rig rig_;
  std::vector<bool> excluded_;
  TrackerOptions options_;
  BodyTemplate body_;
  BodyShape shape_;
  HullPlacement placement_;
  bool initialized_ = false;
  std::vector<TemplatePose> history_;     // accepted poses, most recent last
  std::vector<double> iou_history_;
  std::vector<double> contour_history_;
  // Joints of the limbs that the last accepted frame re-placed (limb search, landmarks): their
  // jump is a correction, not a motion, so the next prediction does not extrapolate it.
  std::vector<int> replaced_joints_;
  // The scale of the pulls towards rest angles that the first frame's fit kept (Initialize).
  double init_rest_prior_scale_ = 0.0;
  std::vector<std::size_t> last_mask_hashes_;
  LandmarkSource landmarks_;
  MaskSource later_masks_;
  FruitlessLimbSearch fruitless_search_;
};

}  // namespace confluent
