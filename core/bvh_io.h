#pragma once
// Reading and writing BVH motion-capture files (Biovision hierarchy) as a Skeleton and Poses.

#include <string>
#include <vector>

#include "core/skeleton.h"

namespace confluent {

// Options for ReadBvh.
struct BvhReadOptions {
  double scale = 1.0;            // multiplies offsets and root translations (e.g. 0.01 for cm -> m)
  bool y_up_to_z_up = false;     // rotate the data from BVH's usual Y-up frame to the world's Z-up
                                 // frame (x stays, y becomes z, z becomes -y)
  bool include_end_sites = true; // add each "End Site" as a joint named "<parent>_end"
};

// A parsed BVH file.
struct BvhMotion {
  Skeleton skeleton;             // joints in file order (parents first); offsets scaled/rotated
  std::vector<Pose> frames;      // one pose per MOTION line; End Sites get identity rotations
  double frame_time_s = 0.0;     // "Frame Time"
  // Per joint (skeleton order), its channel names as written, e.g. {"Zrotation", "Xrotation",
  // "Yrotation"}; empty for End Sites.
  std::vector<std::vector<std::string>> channels;
  std::vector<std::string> warnings;  // e.g. ignored translation channels on non-root joints
};

// Reads a BVH file: any per-joint channel order (rotations composed in the order listed,
// intrinsic: R = R_first * R_second * R_third), End Sites, 3- or 6-channel joints (CMU,
// 3ds Max and MakeHuman exports). The root's position channels become Pose::root_translation
// (added to the root offset). Throws InputError "<path>: line N: ..." on a missing file, bad
// syntax, an unknown channel, a truncated hierarchy or motion block, or a wrong value count.
BvhMotion ReadBvh(const std::string& path, const BvhReadOptions& options = {});

// Writes a BVH file (Y-up, centimetres, as most BVH tools expect): root with 6 channels
// (Xposition Yposition Zposition Zrotation Xrotation Yrotation), other joints with 3
// rotation channels (Z X Y), childless joints as End Sites. `skeleton` and `poses` are in the
// world frame (Z up, metres); read it back with ReadBvh({scale = 0.01, y_up_to_z_up = true}).
// Written atomically; throws OutputError on failure.
void WriteBvh(const std::string& path, const Skeleton& skeleton, const std::vector<Pose>& poses, double frame_time_s);

}  // namespace confluent
