#include "core/body_segments.h"

namespace confluent {
namespace {
const char* const kSegmentNames[kNumBodySegments] = {
    "head",          "neck",          "upper_torso", "lower_torso", "left_upper_arm", "left_forearm",
    "left_hand",     "right_upper_arm", "right_forearm", "right_hand", "left_thigh",  "left_shank",
    "left_foot",     "right_thigh",   "right_shank", "right_foot"};
}  // namespace

std::string BodySegmentName(int segment) {
  return segment >= 0 && segment < kNumBodySegments ? kSegmentNames[segment] : "unknown";
}

int BodySegmentFromName(const std::string& name) {
  for (int i = 0; i < kNumBodySegments; ++i)
    if (name == kSegmentNames[i]) return i;
  return -1;
}

}  // namespace confluent
