#pragma once
// A ring of n cameras 3.6 m from the vertical axis, looking at `target`, alternate cameras
// `height_step_m` higher, focal length 1.1 x width: the tracking tests' rig.

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "calib/camera.h"

namespace confluent::testing {

inline Rig CameraRing(int n, int width, int height, double phase_rad = 0.2, double height_m = 1.5,
                      double height_step_m = 0.4, const Eigen::Vector3d& target = Eigen::Vector3d(0, 0, 1.0)) {
  Rig rig;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n + phase_rad;
    rig.cameras.push_back(LookAtCamera("cam" + std::to_string(i),
                                       Eigen::Vector3d(3.6 * std::sin(a), 3.6 * std::cos(a), height_m + height_step_m * (i % 2)),
                                       target, width, height, 1.1 * width));
  }
  return rig;
}

}  // namespace confluent::testing
