#pragma once
// INTERNAL (tracking/tracker*.cc only): the flag prefixes of a limb that the tracker re-placed, as
// poses.json records them (then the limb's name, e.g. "limb:left_arm").

namespace confluent::tracker_flags {

inline constexpr const char* kLimbSearchFlag = "limb:";   // the lost-limb search (Tracker::SearchLimbs)
inline constexpr const char* kLandmarksFlag = "landmarks:";  // turned onto the landmarks
inline constexpr const char* kArmTwistFlag = "twist:";    // turned about the upper arm (SearchArmTwists)

}  // namespace confluent::tracker_flags
