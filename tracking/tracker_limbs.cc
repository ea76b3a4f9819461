// The tracker's limb searches: lost limbs in canonical placements, limbs turned onto the
// landmarks, and arms turned about their own axis (tracking/tracker.h).

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "tracking/landmark_limbs.h"
#include "tracking/limb_hypotheses.h"
#include "tracking/tracker.h"
#include "tracking/tracker_flags.h"

namespace confluent {

using namespace tracker_flags;

TrackedFrame Tracker::FitLimbHypothesis(const TemplatePose& hypothesis, int frame, const std::vector<Image>& masks,
                                        const std::vector<bool>& use, const SilhouetteObservations& observations) {
  SilhouetteFitOptions fit = options_.fit;
  fit.prior_weight = 0.2;  // towards the hypothesis itself
  fit.coarse_to_fine = false;
  if (!initialized_) fit.rest_prior_scale = init_rest_prior_scale_;  // as Initialize chose
  TrackedFrame candidate;
  candidate.frame = frame;
  candidate.pose = hypothesis;
  candidate.fit = FitTemplateToSilhouettes(body_, observations, fit, &shape_, &candidate.pose);
  Evaluate(shape_, masks, use, &candidate);
  return candidate;
}

std::vector<TemplatePose> Tracker::BestUnfitted(const std::vector<TemplatePose>& hypotheses, int count,
                                                const std::vector<Image>& masks, const std::vector<bool>& use) const {
  std::vector<TrackedFrame> scored;
  for (const TemplatePose& hypothesis : hypotheses) {
    TrackedFrame candidate;
    candidate.pose = hypothesis;
    Evaluate(shape_, masks, use, &candidate);
    scored.push_back(std::move(candidate));
  }
  const int keep = std::min<int>(count, static_cast<int>(scored.size()));
  std::partial_sort(scored.begin(), scored.begin() + keep, scored.end(),
                    [](const TrackedFrame& a, const TrackedFrame& b) { return a.mean_iou > b.mean_iou; });
  std::vector<TemplatePose> best;
  for (int k = 0; k < keep; ++k) best.push_back(scored[k].pose);
  return best;
}

TemplatePose Tracker::WithBestHand(const TemplatePose& pose, Limb arm, const std::vector<Image>& masks,
                                   const std::vector<bool>& use) const {
  if (!IsArm(arm) || options_.hand_rebend_flex_deg.empty() ||
      std::abs(pose.dofs[LimbJoints(arm).end][0]) < options_.hand_rebend_min_rad)
    return pose;
  std::vector<TemplatePose> hands = HandBends(body_, pose, arm, options_.hand_rebend_flex_deg);
  hands.push_back(pose);
  return BestUnfitted(hands, 1, masks, use).front();
}

void Tracker::SearchLimbs(const std::vector<Image>& masks, const std::vector<bool>& use,
                          const SilhouetteObservations& observations, int fits, TrackedFrame* result) {
  for (Limb limb : kAllLimbs) {
    std::vector<TemplatePose> placements = LimbHypotheses(body_, result->pose, limb);
    for (TemplatePose& placement : placements) placement = WithBestHand(placement, limb, masks, use);
    for (const TemplatePose& hypothesis : BestUnfitted(placements, fits, masks, use)) {
      TrackedFrame candidate = FitLimbHypothesis(hypothesis, result->frame, masks, use, observations);
      if (candidate.mean_iou > result->mean_iou + options_.limb_min_gain) {
        candidate.flags = result->flags;
        candidate.flags.push_back(kLimbSearchFlag + std::string(LimbName(limb)));
        *result = std::move(candidate);
      }
    }
  }
}

void Tracker::SearchArmTwists(const std::vector<Image>& masks, const std::vector<bool>& use,
                              const SilhouetteObservations& observations, int fits, TrackedFrame* result) {
  if (!options_.arm_twist_search) return;
  for (Limb arm : {Limb::kLeftArm, Limb::kRightArm}) {
    if (result->pose.dofs[LimbJoints(arm).middle][0] > options_.arm_twist_max_elbow_rad) continue;
    const std::vector<TemplatePose> hypotheses = ArmTwistHypotheses(body_, result->pose, arm, options_.arm_twist_bend_rad);
    TrackedFrame best;
    for (const TemplatePose& hypothesis : BestUnfitted(hypotheses, fits, masks, use)) {
      TrackedFrame candidate = FitLimbHypothesis(hypothesis, result->frame, masks, use, observations);
      if (candidate.mean_iou > result->mean_iou + options_.arm_twist_min_gain &&
          (best.joints.empty() || candidate.mean_iou > best.mean_iou))
        best = std::move(candidate);
    }
    if (best.joints.empty()) continue;
    best.flags = result->flags;
    best.flags.push_back(kArmTwistFlag + std::string(LimbName(arm)));
    best.limb_search = result->limb_search;
    *result = std::move(best);
  }
}

double LandmarkIouTolerance(const TrackerOptions& options, double disagreement_m) {
  const double ramp = (disagreement_m - options.landmark_disagreement_m) /
                      (options.landmark_full_tolerance_m - options.landmark_disagreement_m);
  return options.landmark_iou_tolerance * std::clamp(ramp, 0.0, 1.0);
}

void Tracker::SettleLimbsByLandmarks(const std::vector<Image>& masks, const std::vector<bool>& use,
                                     const SilhouetteObservations& observations, TrackedFrame* result) {
  if (!landmarks_) return;
  const std::shared_ptr<const LandmarkJoints> found = landmarks_(result->frame);
  if (!found) return;
  const LandmarkJoints& landmarks = *found;
  for (Limb limb : kAllLimbs) {
    // A skirt that hangs below the ankle hides the leg: neither the landmarks nor the silhouettes
    // say more than the tracked leg does (on the real Tsinghua frame, turning both legs cost 0.003
    // of held-out IoU). Under a shorter skirt the shank shows and the landmarks place it (samba's
    // knee-length skirt: scan IoU 0.9502 -> 0.9561 with its legs turned).
    if (SkirtHidesAnkle(body_, shape_, result->pose, limb)) continue;
    const double before = LimbDisagreement(result->joints, landmarks, limb);
    if (before < options_.landmark_disagreement_m) continue;  // agrees, or the landmarks do not place it
    const double tolerance = LandmarkIouTolerance(options_, before);
    TrackedFrame best;
    for (TemplatePose hypothesis : LimbsFromLandmarks(body_, shape_, result->pose, limb, landmarks)) {
      hypothesis = WithBestHand(hypothesis, limb, masks, use);
      TrackedFrame candidate = FitLimbHypothesis(hypothesis, result->frame, masks, use, observations);
      const double after = LimbDisagreement(candidate.joints, landmarks, limb);
      // Closer to the landmarks for the same overlap, or a little closer for a better one (a
      // detector misplaces a wrist folded before the chest by 7-10 cm, so a fit that finds the
      // true wrist comes only 2-3 cm closer to theirs).
      const bool closer =
          after <= before - options_.landmark_min_approach_m && candidate.mean_iou >= result->mean_iou - tolerance;
      const bool better = after < before && candidate.mean_iou >= result->mean_iou + options_.limb_min_gain;
      if ((closer || better) && (best.joints.empty() || candidate.mean_iou > best.mean_iou))
        best = std::move(candidate);
    }
    if (best.joints.empty()) continue;
    best.flags = result->flags;
    best.flags.push_back(kLandmarksFlag + std::string(LimbName(limb)));
    *result = std::move(best);
  }
  const double gap = options_.landmark_hand_max_wrist_gap_m;
  for (Limb arm : {Limb::kLeftArm, Limb::kRightArm}) {
    const double before = HandDisagreementRad(result->joints, landmarks, arm, gap);
    if (before < options_.landmark_hand_disagreement_rad) continue;  // agrees, or unknown
    const std::optional<TemplatePose> hypothesis = HandFromLandmarks(body_, shape_, result->pose, arm, landmarks, gap);
    if (!hypothesis) continue;
    TrackedFrame candidate = FitLimbHypothesis(*hypothesis, result->frame, masks, use, observations);
    const double after = HandDisagreementRad(candidate.joints, landmarks, arm, gap);
    if (after > before - options_.landmark_hand_min_approach_rad ||
        candidate.mean_iou < result->mean_iou - options_.landmark_hand_iou_tolerance)
      continue;
    candidate.flags = result->flags;
    candidate.flags.push_back(kLandmarksFlag + std::string(arm == Limb::kLeftArm ? "left_hand" : "right_hand"));
    *result = std::move(candidate);
  }
}

}  // namespace confluent
