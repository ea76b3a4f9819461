#include "calib/plate_colour.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.h"

namespace confluent {
namespace {

// A textured floor (at height floor_z) seen by `camera` through a sensor with RGB `gain`; black
// where the ray misses the floor.
Image FloorPlate(const Camera& camera, const Eigen::Vector3d& gain, double floor_z = 0.0) {
  Image plate(camera.width, camera.height, 3);
  const Eigen::Vector3d centre = camera.center_in_world();
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const Eigen::Vector3d ray = camera.Unproject(Eigen::Vector2d(x, y), 1.0) - centre;
      if (!(ray.z() < -1e-6)) continue;
      const Eigen::Vector3d floor = centre - ((centre.z() - floor_z) / ray.z()) * ray;
      const Eigen::Vector3d albedo(120 + 50 * std::sin(3 * floor.x()), 110 + 40 * std::cos(2 * floor.y()),
                                   90 + 30 * std::sin(floor.x() + floor.y()));
      for (int c = 0; c < 3; ++c)
        plate.data[3 * (y * camera.width + x) + c] =
            static_cast<std::uint8_t>(std::lround(std::min(255.0, albedo[c] * gain[c])));
    }
  return plate;
}

TEST(PlateColourGain, RecoversTheGainRatioOfTwoCamerasSeeingTheFloor) {
  const Camera a = LookAtCamera("a", {3, 0, 1.5}, {0, 0, 0.5}, 160, 120, 120);
  const Camera b = LookAtCamera("b", {0, 3, 2.0}, {0, 0, 0.5}, 160, 120, 120);
  const Eigen::Vector3d gain_a(0.95, 1.02, 1.04), gain_b(1.06, 0.97, 0.93);
  const std::optional<Eigen::Vector3d> gain = PlateColourGain(a, FloorPlate(a, gain_a), b, FloorPlate(b, gain_b));
  ASSERT_TRUE(gain.has_value());
  for (int c = 0; c < 3; ++c) EXPECT_NEAR((*gain)[c], gain_b[c] / gain_a[c], 0.01) << c;
  // The other way round: the inverse.
  const std::optional<Eigen::Vector3d> back = PlateColourGain(b, FloorPlate(b, gain_b), a, FloorPlate(a, gain_a));
  ASSERT_TRUE(back.has_value());
  for (int c = 0; c < 3; ++c) EXPECT_NEAR((*back)[c] * (*gain)[c], 1.0, 0.015) << c;
}

TEST(PlateColourGain, CamerasThatShareNoFloorGiveNoEstimate) {
  const Camera a = LookAtCamera("a", {3, 0, 1.5}, {0, 0, 0.5}, 160, 120, 120);
  const Camera up = LookAtCamera("up", {0, 3, 1.0}, {0, 6, 3.0}, 160, 120, 120);  // looks away, above the horizon
  EXPECT_FALSE(PlateColourGain(a, FloorPlate(a, Eigen::Vector3d::Ones()), up, FloorPlate(up, Eigen::Vector3d::Ones())));
}

// A floor that is not at z = 0: the points compared are not the same, the ratios scatter, and no
// gain is claimed.
TEST(PlateColourGain, FloorAwayFromZeroGivesNoEstimate) {
  const Camera a = LookAtCamera("a", {3, 0, 1.5}, {0, 0, 0.5}, 160, 120, 120);
  const Camera b = LookAtCamera("b", {0, 3, 2.0}, {0, 0, 0.5}, 160, 120, 120);
  const Eigen::Vector3d one = Eigen::Vector3d::Ones();
  EXPECT_FALSE(PlateColourGain(a, FloorPlate(a, one, 0.4), b, FloorPlate(b, one, 0.4)));
  EXPECT_TRUE(PlateColourGain(a, FloorPlate(a, one, 0.0), b, FloorPlate(b, one, 0.0)));
}

TEST(PlateColourGain, PlateOfTheWrongSizeIsAnInputError) {
  const Camera a = LookAtCamera("cam07", {3, 0, 1.5}, {0, 0, 0.5}, 160, 120, 120);
  try {
    PlateColourGain(a, Image(100, 120, 3), a, FloorPlate(a, Eigen::Vector3d::Ones()));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cam07"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("100x120"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace confluent
