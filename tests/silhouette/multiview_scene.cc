#include "tests/silhouette/multiview_scene.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace confluent::testing {

Rig MakeRingRig(int count, int width, int height) {
  Rig rig;
  for (int i = 0; i < count; ++i) {
    const double angle = 2 * M_PI * i / count + 0.3;
    const Eigen::Vector3d centre(3.0 * std::cos(angle), 3.0 * std::sin(angle), 1.4);
    rig.cameras.push_back(LookAtCamera("cam" + std::to_string(i), centre, Eigen::Vector3d(0, 0, 1.0), width, height,
                                       0.9 * width));
  }
  return rig;
}

std::vector<Ellipsoid> MakeActor(double x, double y, double arm) {
  std::vector<Ellipsoid> actor;
  actor.push_back({{x - 0.1, y, 0.45}, {0.08, 0.08, 0.45}, {40, 50, 120}});     // left leg: blue trousers
  actor.push_back({{x + 0.1, y, 0.45}, {0.08, 0.08, 0.45}, {40, 50, 120}});     // right leg
  actor.push_back({{x, y, 1.2}, {0.2, 0.13, 0.35}, {200, 60, 50}});             // torso: red shirt
  actor.push_back({{x, y, 1.68}, {0.1, 0.1, 0.12}, {220, 170, 140}});            // head: skin
  actor.push_back({{x - 0.25, y, 1.15}, {0.05, 0.05, 0.3}, {200, 60, 50}});      // left arm, hanging
  // Right arm: from hanging (arm = 0) to held out sideways (arm = 1).
  const double lift = std::clamp(arm, 0.0, 1.0);
  actor.push_back({{x + 0.25 + 0.25 * lift, y, 1.15 + 0.3 * lift}, {0.05 + 0.25 * lift, 0.05, 0.3 - 0.25 * lift},
                   {220, 170, 140}});
  return actor;
}

namespace {

// Distance along the ray (origin o, unit direction d) to the nearest ellipsoid, and its index.
bool Hit(const std::vector<Ellipsoid>& actor, const Eigen::Vector3d& o, const Eigen::Vector3d& d, int* index,
         double* slant) {
  double best = 1e30;
  for (std::size_t k = 0; k < actor.size(); ++k) {
    const Eigen::Vector3d oc = (o - actor[k].center).cwiseQuotient(actor[k].radii);
    const Eigen::Vector3d dc = d.cwiseQuotient(actor[k].radii);
    const double a = dc.squaredNorm(), b = 2 * oc.dot(dc), c = oc.squaredNorm() - 1;
    const double disc = b * b - 4 * a * c;
    if (disc < 0) continue;
    const double t = (-b - std::sqrt(disc)) / (2 * a);
    if (t > 0 && t < best) {
      best = t;
      *index = static_cast<int>(k);
      const Eigen::Vector3d normal = (oc + t * dc).cwiseQuotient(actor[k].radii).normalized();
      *slant = std::abs(normal.dot(d));
    }
  }
  return best < 1e29;
}

}  // namespace

Image RenderMask(const Camera& camera, const std::vector<Ellipsoid>& actor) {
  Image mask(camera.width, camera.height, 1);
  const Eigen::Vector3d origin = camera.center_in_world();
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      int index = 0;
      double slant = 0;
      if (Hit(actor, origin, camera.RayInWorld(Eigen::Vector2d(x, y)), &index, &slant)) mask.at<std::uint8_t>(x, y) = 255;
    }
  return mask;
}

Image RenderFrame(const Camera& camera, const std::vector<Ellipsoid>& actor, const Image& background) {
  Image frame = background;
  const Eigen::Vector3d origin = camera.center_in_world();
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      int index = 0;
      double slant = 0;
      if (!Hit(actor, origin, camera.RayInWorld(Eigen::Vector2d(x, y)), &index, &slant)) continue;
      const double shade = 0.55 + 0.45 * slant;
      for (int c = 0; c < 3; ++c)
        frame.at<std::uint8_t>(x, y, c) =
            static_cast<std::uint8_t>(std::clamp(std::lround(shade * actor[index].colour[c]), 0L, 255L));
    }
  return frame;
}

}  // namespace confluent::testing
