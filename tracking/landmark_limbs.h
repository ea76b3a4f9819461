#pragma once
// Limbs placed where triangulated landmarks say they are (tracking/landmark_joints.h): how far a
// pose's limb lies from them, and the pose with that limb turned onto them.

#include <optional>
#include <vector>

#include "tracking/body_template.h"
#include "tracking/landmark_joints.h"
#include "tracking/limb_hypotheses.h"

namespace confluent {

// The distance (m) between the end joint of `limb` (wrist or ankle) in `joints` (template order,
// world) and the landmarks'; -1 when the landmarks do not place it.
double LimbDisagreement(const std::vector<Eigen::Vector3d>& joints, const LandmarkJoints& landmarks, Limb limb);

// Whether the template's skirt (BodyShape::skirt_length_m) hides the ankle of `limb`, a leg, in
// `pose`: its hem, the lowest point of the lower torso's capsule, hangs below the ankle. A
// detector then guesses the leg, and the silhouettes hold only the skirt. False for an arm and
// without a skirt.
bool SkirtHidesAnkle(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& pose, Limb limb);

// `pose` with `limb` turned towards the landmarks, the template's bone lengths kept and the rest
// of the body unchanged, in two ways: the lower bone alone pointed at the landmarks' wrist or
// ankle (the elbow or knee held: a forearm folded the wrong way), and both bones pointed as the
// landmarks' are (when they place the elbow or knee). None when the landmarks do not place the
// end joint.
std::vector<TemplatePose> LimbsFromLandmarks(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& pose,
                                             Limb limb, const LandmarkJoints& landmarks);

// The angle (rad) between the hand of `arm` in `joints` (template order, world; wrist to hand end)
// and the landmarks' (their wrist to their knuckles); -1 when the landmarks do not place both,
// place the knuckles within 3 cm of the wrist (no direction), or place the wrist more than
// `max_wrist_gap_m` from `joints`' (a detector that misplaces the wrist points the hand anywhere:
// on the Indian dance, wrists 7-9 cm off came with hands 50-140 degrees off).
double HandDisagreementRad(const std::vector<Eigen::Vector3d>& joints, const LandmarkJoints& landmarks, Limb arm,
                           double max_wrist_gap_m);

// `pose` with the hand of `arm` turned at the wrist to point as the landmarks' hand does (see
// HandDisagreementRad), the rest of the body held; none when they do not place it.
std::optional<TemplatePose> HandFromLandmarks(const BodyTemplate& body, const BodyShape& shape,
                                              const TemplatePose& pose, Limb arm, const LandmarkJoints& landmarks,
                                              double max_wrist_gap_m);

}  // namespace confluent
