#include "studio/rig.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/error.h"

namespace confluent {

void StudioRigOptions::Check() const {
  const std::string owner = "StudioRigOptions.";
  RequireOption(num_ring_cameras >= 1 && num_ring_cameras <= 256, owner + "num_ring_cameras", num_ring_cameras,
                "in [1, 256]");
  RequireOption(num_heldout_cameras >= 0 && num_heldout_cameras <= 64, owner + "num_heldout_cameras",
                num_heldout_cameras, "in [0, 64]");
  RequireOption(ring_radius_m > 0.5, owner + "ring_radius_m", ring_radius_m, "> 0.5 metres");
  RequireOption(heldout_radius_m > 0.5, owner + "heldout_radius_m", heldout_radius_m, "> 0.5 metres");
  RequireOption(width_px >= 16 && width_px <= 16384, owner + "width_px", width_px, "in [16, 16384] pixels");
  RequireOption(height_px >= 16 && height_px <= 16384, owner + "height_px", height_px, "in [16, 16384] pixels");
  RequireOption(focal_px >= 0.0 && std::isfinite(focal_px), owner + "focal_px", focal_px,
                ">= 0 and finite (0 = automatic)");
  RequireOption(std::isfinite(k1) && std::abs(k1) <= 0.5, owner + "k1", k1, "in [-0.5, 0.5]");
  RequireOption(intrinsics_jitter >= 0.0 && intrinsics_jitter < 0.2, owner + "intrinsics_jitter", intrinsics_jitter,
                "in [0, 0.2)");
  const Eigen::Vector3d& target = target_in_world;
  RequireOption(target.allFinite(), owner + "target_in_world", {target.x(), target.y(), target.z()}, "finite");
}

Rig MakeStudioRig(const StudioRigOptions& options) {
  options.Check();
  std::mt19937 rng(options.seed * 7919u + 13u);
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  const double focal = options.focal_px > 0.0 ? options.focal_px : 1.1 * options.width_px;
  auto make = [&](const std::string& name, double azimuth_deg, double radius, double height) {
    const double a = azimuth_deg * M_PI / 180.0;
    const Eigen::Vector3d center = options.target_in_world.cwiseProduct(Eigen::Vector3d(1, 1, 0)) +
                                   Eigen::Vector3d(-radius * std::sin(a), radius * std::cos(a), height);
    Camera camera = LookAtCamera(name, center, options.target_in_world, options.width_px, options.height_px,
                                 focal * (1.0 + options.intrinsics_jitter * jitter(rng)));
    camera.K(1, 1) = camera.K(0, 0);
    camera.K(0, 2) += options.intrinsics_jitter * 0.5 * options.width_px * 0.1 * jitter(rng);
    camera.K(1, 2) += options.intrinsics_jitter * 0.5 * options.height_px * 0.1 * jitter(rng);
    camera.dist(0) = options.k1;
    return camera;
  };
  Rig rig;
  const double step = 360.0 / options.num_ring_cameras;
  for (int i = 0; i < options.num_ring_cameras; ++i) {
    char name[16];
    std::snprintf(name, sizeof(name), "cam%02d", i);
    rig.cameras.push_back(
        make(name, i * step, options.ring_radius_m, options.ring_height_m + (i % 2) * options.ring_height_step_m));
  }
  const double heldout_heights[] = {0.9, 2.7, 1.3, 2.2};
  for (int i = 0; i < options.num_heldout_cameras; ++i) {
    // Between ring cameras, spread around the circle.
    const double azimuth = (0.5 + std::floor(i * options.num_ring_cameras / std::max(1.0, options.num_heldout_cameras * 1.0))) * step + 7.0 * i;
    rig.cameras.push_back(make("holdout" + std::to_string(i), azimuth, options.heldout_radius_m, heldout_heights[i % 4]));
  }
  return rig;
}

double CaptureVolumeRadius(const Rig& rig, int num_ring_cameras, const Eigen::Vector3d& target_in_world,
                           double performer_height_m) {
  const int cameras = std::min(num_ring_cameras, rig.size());
  // The performer's envelope: a column (the body, arms raised over the head) and, at shoulder
  // height, a disc of the arms' span; 12 points on each circle.
  const double h = performer_height_m;
  const std::array<std::array<double, 2>, 4> circles = {{{0.17 * h, 0.0}, {0.17 * h, 0.6 * h}, {0.17 * h, 1.2 * h},
                                                         {0.5 * h, 0.8 * h}}};  // radius, height
  auto fits = [&](double r) {
    for (int direction = 0; direction < 16; ++direction) {
      const double a = 2 * M_PI * direction / 16;
      const Eigen::Vector3d centre(target_in_world.x() + r * std::cos(a), target_in_world.y() + r * std::sin(a), 0.0);
      for (int c = 0; c < cameras; ++c) {
        const Camera& camera = rig.cameras[c];
        for (int k = 0; k < 12; ++k)
          for (const auto& [radius, z] : circles) {
            const double b = 2 * M_PI * k / 12;
            const Eigen::Vector3d point = centre + Eigen::Vector3d(radius * std::cos(b), radius * std::sin(b), z);
            Eigen::Vector2d pixel;
            if (!camera.ProjectChecked(point, &pixel) || pixel.x() < 0 || pixel.y() < 0 || pixel.x() > camera.width ||
                pixel.y() > camera.height)
              return false;
          }
      }
    }
    return true;
  };
  if (!fits(0.0)) return 0.0;
  double inside = 0.0, outside = 20.0;
  while (outside - inside > 0.01) {
    const double r = 0.5 * (inside + outside);
    (fits(r) ? inside : outside) = r;
  }
  return inside;
}

}  // namespace confluent
