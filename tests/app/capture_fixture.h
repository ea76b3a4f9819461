#pragma once
// A small generated recorded camera folder for end-to-end tests: cameras in a ring looking
// at a sphere "actor" at (0, 0, 1); images, and masks that are exact projections.

#include <string>

#include "calib/camera.h"

namespace confluent::testing {

struct FixtureOptions {
  int num_cameras = 4;
  int num_frames = 3;
  int width = 96;
  int height = 72;
  bool write_masks = true;
  double sphere_radius_m = 0.5;
};

// The ring rig the fixture uses (radius 3 m, height 1.2 m, looking at (0, 0, 1)).
Rig FixtureRig(const FixtureOptions& options);

// Writes CAPTURE/intri.yml, extri.yml, images/<cam>/<frame>.png and (optionally) masks/.
void WriteFixtureCapture(const std::string& capture_dir, const FixtureOptions& options = {});

}  // namespace confluent::testing
