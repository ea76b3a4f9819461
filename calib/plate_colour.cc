#include "calib/plate_colour.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/image_io.h"

namespace confluent {
namespace {

void CheckPlate(const Camera& camera, const Image& plate, const std::string& source = "plate") {
  if (plate.width != camera.width || plate.height != camera.height || plate.channels != 3 ||
      plate.type != PixelType::kUInt8)
    throw InputError(source, "clean plate of camera " + camera.name + " must be an RGB 8-bit image of " +
                                  std::to_string(camera.width) + "x" + std::to_string(camera.height) + ", got " +
                                  std::to_string(plate.width) + "x" + std::to_string(plate.height) + "x" +
                                  std::to_string(plate.channels));
}

// The 3x3 mean colour around the pixel nearest to `pixel`, or false when it is not inside the
// image with a one-pixel margin.
bool MeanColour(const Image& image, const Eigen::Vector2d& pixel, Eigen::Vector3d* colour) {
  const long x = std::lround(pixel.x()), y = std::lround(pixel.y());
  if (!(x >= 1 && y >= 1 && x < image.width - 1 && y < image.height - 1)) return false;
  colour->setZero();
  for (long dy = -1; dy <= 1; ++dy)
    for (long dx = -1; dx <= 1; ++dx)
      for (int c = 0; c < 3; ++c) (*colour)[c] += image.data[3 * ((y + dy) * image.width + x + dx) + c];
  *colour /= 9.0;
  return true;
}

}  // namespace

std::optional<Eigen::Vector3d> PlateColourGain(const Camera& from, const Image& from_plate, const Camera& to,
                                               const Image& to_plate, const PlateColourOptions& options) {
  CheckPlate(from, from_plate);
  CheckPlate(to, to_plate);
  std::vector<double> ratios[3];
  const int steps = static_cast<int>(std::floor(options.floor_extent_m / options.floor_step_m));
  for (int i = -steps; i <= steps; ++i)
    for (int j = -steps; j <= steps; ++j) {
      const Eigen::Vector3d point(i * options.floor_step_m, j * options.floor_step_m, 0.0);
      Eigen::Vector2d a, b;
      Eigen::Vector3d colour_from, colour_to;
      if (!from.ProjectChecked(point, &a) || !to.ProjectChecked(point, &b)) continue;
      if (!MeanColour(from_plate, a, &colour_from) || !MeanColour(to_plate, b, &colour_to)) continue;
      if (colour_from.minCoeff() < options.min_level || colour_to.minCoeff() < options.min_level) continue;
      for (int c = 0; c < 3; ++c) ratios[c].push_back(colour_to[c] / colour_from[c]);
    }
  if (static_cast<int>(ratios[0].size()) < options.min_samples) return std::nullopt;
  Eigen::Vector3d gain;
  for (int c = 0; c < 3; ++c) {
    std::vector<double>& r = ratios[c];
    std::sort(r.begin(), r.end());
    gain[c] = r[r.size() / 2];
    if (r[3 * r.size() / 4] - r[r.size() / 4] > options.max_ratio_spread * gain[c]) return std::nullopt;
  }
  return gain;
}

std::vector<Eigen::Vector3d> PlateColourGainsTo(const Capture& capture, const std::vector<int>& from, int to,
                                                const Image& to_plate, std::vector<std::string>* unmatched,
                                                const PlateColourOptions& options) {
  const Rig& rig = capture.rig();
  const std::string to_path = capture.BackgroundPath(to);
  CheckPlate(rig.cameras[to], to_plate, to_path.empty() ? capture.root() + "/background" : to_path);
  std::vector<Eigen::Vector3d> gains;
  for (int camera : from) {
    const std::string path = capture.BackgroundPath(camera);
    std::optional<Eigen::Vector3d> gain;
    if (!path.empty()) {
      const Image plate = ToRgb8(ReadImage(path));
      CheckPlate(rig.cameras[camera], plate, path);
      gain = PlateColourGain(rig.cameras[camera], plate, rig.cameras[to], to_plate, options);
    }
    if (!gain && unmatched) unmatched->push_back(rig.cameras[camera].name);
    gains.push_back(gain.value_or(Eigen::Vector3d::Ones()));
  }
  return gains;
}

}  // namespace confluent
