#pragma once
// Other places a limb may be, for re-initialising a limb the tracker has lost (an arm left
// across the torso while the real one is raised): each hypothesis is the given pose with one
// limb moved to a canonical placement (arm down, spread, raised, forward, across the chest ...;
// leg straight, forward, kicking, sideways, back), the elbow or knee straight or bent.
// Directions are relative to the torso (the chest for arms, the pelvis for legs).

#include <vector>

#include "tracking/body_template.h"

namespace confluent {

enum class Limb { kLeftArm, kRightArm, kLeftLeg, kRightLeg };
constexpr Limb kAllLimbs[] = {Limb::kLeftArm, Limb::kRightArm, Limb::kLeftLeg, Limb::kRightLeg};

// "left_arm", "right_arm", "left_leg", "right_leg".
const char* LimbName(Limb limb);

// Whether `limb` is an arm (else a leg).
inline bool IsArm(Limb limb) { return limb == Limb::kLeftArm || limb == Limb::kRightArm; }

// A limb's chain: shoulder, elbow, wrist or hip, knee, ankle.
struct LimbChain {
  int root, middle, end;
};
LimbChain LimbJoints(Limb limb);

// `pose` with `limb` moved to each canonical placement (within the joint limits), the rest of
// the body unchanged.
std::vector<TemplatePose> LimbHypotheses(const BodyTemplate& body, const TemplatePose& pose, Limb limb);

// `pose` with `arm`'s upper arm turned about its own axis by 90, 180 and -90 degrees and the
// elbow bent to at least `bend_rad` (within the limits). A nearly straight arm turns about its
// axis without changing its silhouette, so the fit keeps whatever twist it has; when the arm then
// bends, the elbow's hinge lies in the wrong plane and the fit keeps the arm straight instead.
std::vector<TemplatePose> ArmTwistHypotheses(const BodyTemplate& body, const TemplatePose& pose, Limb arm,
                                             double bend_rad);

// `pose` with the hand of `arm` bent at the wrist to each of `flex_deg` (about the wrist's
// flexion axis, within its limits; no sideways bend). A limb turned onto new joints keeps its old
// wrist angles, so its hand may point out of the silhouettes, and the fit then folds the forearm
// to hide the hand (the Indian dance's hands turned in before the chest: the refitted wrist
// 11 cm from the truth it started on).
std::vector<TemplatePose> HandBends(const BodyTemplate& body, const TemplatePose& pose, Limb arm,
                                    const std::vector<double>& flex_deg);

}  // namespace confluent
