#include "tests/app/capture_fixture.h"

#include <cmath>
#include <cstdio>

#include "calib/easymocap_io.h"
#include "core/image_io.h"

namespace confluent::testing {

Rig FixtureRig(const FixtureOptions& options) {
  Rig rig;
  const Eigen::Vector3d target(0, 0, 1);
  for (int i = 0; i < options.num_cameras; ++i) {
    const double angle = 2 * M_PI * i / options.num_cameras;
    const Eigen::Vector3d center(3 * std::cos(angle), 3 * std::sin(angle), 1.2);
    char name[16];
    std::snprintf(name, sizeof name, "cam%02d", i);
    const Camera camera = LookAtCamera(name, center, target, options.width, options.height, options.width * 0.9);
    rig.cameras.push_back(camera);
  }
  return rig;
}

void WriteFixtureCapture(const std::string& capture_dir, const FixtureOptions& options) {
  const Rig rig = FixtureRig(options);
  WriteEasyMocap(rig, capture_dir);
  const Eigen::Vector3d sphere_center(0, 0, 1);
  for (const Camera& camera : rig.cameras) {
    for (int frame = 0; frame < options.num_frames; ++frame) {
      Image image(camera.width, camera.height, 3), mask(camera.width, camera.height, 1);
      for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
          // Exact ray-sphere test per pixel centre.
          const Eigen::Vector3d ray = camera.RayInWorld(Eigen::Vector2d(x, y));
          const Eigen::Vector3d to_center = sphere_center - camera.center_in_world();
          const double along = to_center.dot(ray);
          const bool hit = (to_center - along * ray).norm() < options.sphere_radius_m && along > 0;
          mask.at<std::uint8_t>(x, y) = hit ? 255 : 0;
          for (int c = 0; c < 3; ++c)
            image.at<std::uint8_t>(x, y, c) = hit ? static_cast<std::uint8_t>(200 - 40 * c) : static_cast<std::uint8_t>(40 + frame);
        }
      char name[32];
      std::snprintf(name, sizeof name, "%06d.png", frame);
      WriteImage(capture_dir + "/images/" + camera.name + "/" + name, image);
      if (options.write_masks) WriteImage(capture_dir + "/masks/" + camera.name + "/" + name, mask);
    }
  }
}

}  // namespace confluent::testing
