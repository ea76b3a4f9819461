#pragma once
// Pose2Sim's TOML calibration (Calib_*.toml), in both directions.
//
// One table per camera: name, size = [width, height], matrix (3x3 K), distortions
// (k1 k2 p1 p2 [k3]), rotation (OpenCV Rodrigues vector, cam_from_world), translation
// (cam_from_world, metres), fisheye (true is refused: confluent's camera is the pinhole model).
// Tables without a matrix, such as [metadata], are not cameras. Cameras keep the file's order.

#include <string>

#include "calib/camera.h"

namespace confluent {

// Reads a Pose2Sim calibration. Throws InputError naming the file, the camera and the problem
// (TOML syntax with its line, a missing or malformed key, a fisheye camera, no camera at all).
// The rig is not checked here (ImportCalibration does that).
Rig ReadPose2SimToml(const std::string& path);

// Writes `rig` as a Pose2Sim calibration, atomically; numbers round-trip exactly (17
// significant digits). Throws OutputError(path) when the file cannot be written.
void WritePose2SimToml(const Rig& rig, const std::string& path);

}  // namespace confluent
