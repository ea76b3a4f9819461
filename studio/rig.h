#pragma once
// The studio's camera rig: a ring of cameras around the capture volume plus held-out cameras
// at other azimuths and heights (for evaluation).

#include <Eigen/Core>

#include "calib/camera.h"

namespace confluent {

// Layout and intrinsics of the studio rig. Azimuth 0 is the +y axis (the actor's front at rest),
// increasing counter-clockwise seen from above.
struct StudioRigOptions {
  int num_ring_cameras = 8;       // "cam00", "cam01", ... evenly spaced in azimuth
  int num_heldout_cameras = 2;    // "holdout0", ... between ring cameras, at other heights
  double ring_radius_m = 3.8;     // horizontal distance of ring cameras from the target
  double ring_height_m = 1.6;     // camera height; odd ring cameras are ring_height_step_m higher
  double ring_height_step_m = 0.5;
  double heldout_radius_m = 4.0;
  Eigen::Vector3d target_in_world = Eigen::Vector3d(0.0, 0.0, 1.0);  // every camera looks here
  int width_px = 1024;
  int height_px = 768;
  double focal_px = 0.0;          // 0: 1.1 * width (about 49 degrees horizontal field of view)
  double k1 = 0.0;                // radial distortion k1 of every camera (e.g. -0.05), 0 = none
  double intrinsics_jitter = 0.01;  // relative random spread of focal length and principal point
  unsigned seed = 1;
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// The rig: ring cameras first, then the held-out cameras. Deterministic for given options.
Rig MakeStudioRig(const StudioRigOptions& options = {});

// How far (metres, horizontally) a performer's pelvis may move from the rig's target and stay
// whole in the image of every one of the first `num_ring_cameras` cameras of `rig`: the
// performer is a column of radius 0.17 x height from the floor to 1.2 x height (arms raised over
// the head) and a disc of radius 0.5 x height at shoulder height (arms spread), tried in 16
// directions; found by bisection to 1 cm. 0 when even a performer at the target does not fit.
double CaptureVolumeRadius(const Rig& rig, int num_ring_cameras, const Eigen::Vector3d& target_in_world,
                           double performer_height_m);


}  // namespace confluent
