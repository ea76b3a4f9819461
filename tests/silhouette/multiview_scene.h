#pragma once
// A calibrated ring of cameras around an actor made of ellipsoids, with exact masks: ground
// truth for the multi-view checks and the plate-free background (silhouette/multiview.h,
// silhouette/plate_free.h).

#include <Eigen/Core>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"

namespace confluent::testing {

// `count` cameras of width x height on a circle of 3 m radius, 1.4 m high, looking at (0, 0, 1).
Rig MakeRingRig(int count, int width, int height);

// An axis-aligned ellipsoid with a colour (8-bit RGB).
struct Ellipsoid {
  Eigen::Vector3d center;
  Eigen::Vector3d radii;
  Eigen::Vector3d colour;
};

// A person standing at (x, y) on the floor: legs, torso, head and an arm raised by `arm` in [0, 1].
std::vector<Ellipsoid> MakeActor(double x, double y, double arm);

// Exact mask (0/255) of the ellipsoids in `camera`.
Image RenderMask(const Camera& camera, const std::vector<Ellipsoid>& actor);

// `background` with the ellipsoids drawn over it (colour shaded by the surface's slant).
Image RenderFrame(const Camera& camera, const std::vector<Ellipsoid>& actor, const Image& background);

}  // namespace confluent::testing
