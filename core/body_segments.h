#pragma once
// The 16 body segments of the skeletal template topology, shared by the studio actor, the
// tracker's BodyTemplate and correspondence files ("segment" labels).

#include <string>

namespace confluent {

// The 16 body segments, in this order (also the values of Mesh::face_labels).
enum class BodySegment {
  kHead, kNeck, kUpperTorso, kLowerTorso,
  kLeftUpperArm, kLeftForearm, kLeftHand,
  kRightUpperArm, kRightForearm, kRightHand,
  kLeftThigh, kLeftShank, kLeftFoot,
  kRightThigh, kRightShank, kRightFoot,
};
constexpr int kNumBodySegments = 16;

// snake_case name of a segment ("left_forearm"), or "unknown" when out of range.
std::string BodySegmentName(int segment);

// Segment index of a snake_case name, or -1.
int BodySegmentFromName(const std::string& name);

}  // namespace confluent
