#pragma once
// Writing and reading the tracker's results as poses.json (BVH: core/bvh_io.h).

#include <string>
#include <vector>

#include "core/skeleton.h"
#include "tracking/body_template.h"
#include "tracking/tracker.h"

namespace confluent {

// Writes poses.json: joint names and parents, DOF layout with limits, fitted shape, and per
// frame the root, joint angles (radians), local rotations (w x y z), world joint positions
// (m), overlap per camera, flags and what the lost-limb search did (the tracking state a resumed
// run needs). `camera_names` labels TrackedFrame::camera_iou.
void WritePosesJson(const std::string& path, const BodyTemplate& body, const BodyShape& shape,
                    const std::vector<std::string>& camera_names, const std::vector<TrackedFrame>& frames, double fps);

// The contents of a poses.json file.
struct PosesFile {
  double fps = 25.0;
  BodyShape shape;
  std::vector<std::string> camera_names;  // cameras named in the per-frame overlaps, in rig order when known
  std::vector<TrackedFrame> frames;       // pose, joints (recomputed), mean IoU, flags, seconds
};

// Reads a poses.json written by WritePosesJson (a whole run, or a one-frame tracking state
// file). `camera_names` orders TrackedFrame::camera_iou (-1 where absent); empty: no per-camera
// overlaps. Throws InputError naming the file for missing keys, unknown joints or a wrong
// number of joint angles.
PosesFile ReadPosesJson(const std::string& path, const BodyTemplate& body,
                        const std::vector<std::string>& camera_names = {});

}  // namespace confluent
