#pragma once
// Virtual camera paths for novel-view rendering: an orbit around the actor, a smooth path
// through chosen input cameras, a fixed camera, and a frozen-time ("bullet time") sweep.
// Every path is a list of distortion-free calib/camera.h Cameras, one per output frame.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "calib/camera.h"

namespace confluent {

// An orbit: a camera circling the vertical axis through `center_in_world` (world Z up),
// always looking at `center_in_world`.
struct OrbitPathOptions {
  Eigen::Vector3d center_in_world = Eigen::Vector3d(0.0, 0.0, 1.0);  // look-at point, metres
  double radius_m = 3.0;          // horizontal distance of the camera from the vertical axis
  double height_m = 1.5;          // camera height above the ground plane z = 0
  double start_angle_deg = -90.0; // azimuth of the first camera (0 = +x, 90 = +y); -90 = in front (-y)
  double sweep_deg = 360.0;       // azimuth covered (sign = direction; 360 = full turn)
  int num_frames = 100;           // cameras on the path; a full turn does not repeat the first
  int width_px = 1024;            // image size
  int height_px = 768;
  double vertical_fov_deg = 45.0; // pinhole field of view (square pixels, centred principal point)
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// The orbit cameras, named "orbit_<i>". Throws UsageError for bad options.
std::vector<Camera> OrbitPath(const OrbitPathOptions& options);

// An orbit fitted to a ring of cameras: mean horizontal distance from the vertical axis through
// `center_in_world` and mean height of their centres, the first camera's image size and vertical
// field of view. Throws UsageError when `cameras` is empty.
OrbitPathOptions OrbitAroundCameras(const std::vector<Camera>& cameras, const Eigen::Vector3d& center_in_world);

// A smooth path through key cameras.
struct KeyCameraPathOptions {
  int num_frames = 100;  // cameras on the whole path (>= number of keys)
  // Closed loop: after the last key the path returns to the first (the first key is not
  // repeated at the end). Open: the first and last cameras are the first and last keys.
  bool closed = false;
  // Output image size; 0 = the first key's size. Intrinsics are rescaled to it.
  int width_px = 0;
  int height_px = 0;
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// Interpolates key cameras: centres on a centripetal Catmull-Rom spline, rotations by slerp
// between consecutive keys, intrinsics (K, after rescaling to the output size) blended linearly.
// Key j sits exactly at frame round(j * (num_frames - 1) / (keys - 1)) (open) or
// round(j * num_frames / keys) (closed), with its own centre, rotation and K. The output has no
// lens distortion. Cameras are named "path_<i>". Throws UsageError with fewer than 1 key (2 for
// closed) or too few frames, InputError when a key fails Camera::Check.
std::vector<Camera> PathThroughCameras(const std::vector<Camera>& keys, const KeyCameraPathOptions& options);

// Frame indices of the keys in PathThroughCameras' output (see there).
std::vector<int> KeyFrameIndices(int num_keys, const KeyCameraPathOptions& options);

// `num_frames` copies of `camera`, lens distortion kept, so that rendering into a held-out
// camera matches its real images pixel for pixel. Throws UsageError when num_frames < 1.
std::vector<Camera> FixedPath(const Camera& camera, int num_frames);

// The cameras sorted by azimuth around the vertical axis through `center_in_world`
// (counter-clockwise seen from above), e.g. to sweep around a ring for bullet time.
std::vector<Camera> SortByAzimuth(const std::vector<Camera>& cameras, const Eigen::Vector3d& center_in_world);

// What one output frame of a novel-view sequence shows: a camera and a capture frame.
struct PathFrame {
  Camera camera;
  int frame = 0;  // capture frame index
};

// A moving camera over the sequence: one output frame per entry of `frames`; output frame j
// uses path[round(j * (P - 1) / (M - 1))] (P path cameras, M frames), so a path of any length
// is stretched over the sequence. Throws UsageError when either list is empty.
std::vector<PathFrame> AlongSequence(const std::vector<Camera>& path, const std::vector<int>& frames);

// Frozen time ("bullet time"): every camera of the path shows the same capture frame.
std::vector<PathFrame> FrozenTime(const std::vector<Camera>& path, int frame);

}  // namespace confluent
