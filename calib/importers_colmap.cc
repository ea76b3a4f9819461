// COLMAP cameras.txt / images.txt. COLMAP puts the centre of the top-left pixel at (0.5, 0.5);
// confluent puts it at (0, 0), so principal points move by -0.5.

#include <fstream>
#include <map>
#include <sstream>

#include <Eigen/Geometry>

#include "calib/importers_internal.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace importers_internal {

namespace {

struct ColmapIntrinsics {
  int width = 0, height = 0;
  Eigen::Matrix3d K;
  Vector5d dist = Vector5d::Zero();
};

std::map<int, ColmapIntrinsics> ReadColmapCameras(const std::string& path) {
  std::map<int, ColmapIntrinsics> cameras;
  std::istringstream in(ReadTextFile(path));
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::vector<std::string> tokens = SplitWhitespace(line);
    if (tokens.empty() || tokens[0][0] == '#') continue;
    const std::string where = "line " + std::to_string(line_number);
    if (tokens.size() < 4) throw InputError(path, where + ": expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
    const int id = ParseInt(tokens[0], path, where + " camera id");
    const std::string model = tokens[1];
    ColmapIntrinsics camera;
    camera.width = ParseInt(tokens[2], path, where + " width");
    camera.height = ParseInt(tokens[3], path, where + " height");
    std::vector<double> p;
    for (std::size_t i = 4; i < tokens.size(); ++i) p.push_back(ParseNumber(tokens[i], path, where + " parameter"));
    const std::map<std::string, std::size_t> counts = {{"SIMPLE_PINHOLE", 3}, {"PINHOLE", 4}, {"SIMPLE_RADIAL", 4},
                                                       {"RADIAL", 5}, {"OPENCV", 8}, {"FULL_OPENCV", 12}};
    const auto count = counts.find(model);
    if (count == counts.end())
      throw InputError(path, where + ": unsupported COLMAP camera model " + model +
                                 " (supported: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV)");
    if (p.size() != count->second)
      throw InputError(path, where + ": model " + model + " needs " + std::to_string(count->second) +
                                 " parameters, got " + std::to_string(p.size()));
    if (model == "SIMPLE_PINHOLE" || model == "SIMPLE_RADIAL" || model == "RADIAL") {
      camera.K = IntrinsicMatrix(p[0], p[0], p[1] - 0.5, p[2] - 0.5);
      if (model == "SIMPLE_RADIAL") camera.dist[0] = p[3];
      if (model == "RADIAL") camera.dist.head<2>() << p[3], p[4];
    } else {
      camera.K = IntrinsicMatrix(p[0], p[1], p[2] - 0.5, p[3] - 0.5);
      if (p.size() >= 8) camera.dist.head<4>() << p[4], p[5], p[6], p[7];
      if (model == "FULL_OPENCV") {
        camera.dist[4] = p[8];
        if (p[9] != 0.0 || p[10] != 0.0 || p[11] != 0.0)
          throw InputError(path, where + ": unsupported distortion model with 8 coefficients (FULL_OPENCV with "
                                         "non-zero k4 k5 k6; only k1 k2 p1 p2 k3 are supported)");
      }
    }
    if (!cameras.emplace(id, camera).second)
      throw InputError(path, where + ": camera id " + std::to_string(id) + " appears twice");
  }
  return cameras;
}

}  // namespace

Rig ReadColmap(const std::string& input_path) {
  fs::path folder(input_path);
  std::error_code error;
  if (!fs::is_directory(folder, error)) folder = folder.parent_path();
  const std::string cameras_path = (folder / "cameras.txt").string();
  const std::string images_path = (folder / "images.txt").string();
  if (!fs::exists(cameras_path, error)) throw InputError(cameras_path, "file not found");
  if (!fs::exists(images_path, error)) throw InputError(images_path, "file not found");
  const std::map<int, ColmapIntrinsics> intrinsics = ReadColmapCameras(cameras_path);

  std::istringstream in(ReadTextFile(images_path));
  std::string line;
  int line_number = 0;
  bool expect_points = false;
  std::vector<Camera> cameras;
  std::vector<std::string> image_names;
  while (std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line[0] == '#') continue;
    if (expect_points) {  // the POINTS2D line of the previous image (may be empty)
      expect_points = false;
      continue;
    }
    const std::vector<std::string> tokens = SplitWhitespace(line);
    if (tokens.empty()) continue;
    const std::string where = "line " + std::to_string(line_number);
    if (tokens.size() < 10)
      throw InputError(images_path, where + ": expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME");
    double v[8];
    for (int i = 0; i < 8; ++i) v[i] = ParseNumber(tokens[1 + i], images_path, where);
    const int camera_id = ParseInt(tokens[8], images_path, where + " camera id");
    std::string name = tokens[9];
    for (std::size_t i = 10; i < tokens.size(); ++i) name += " " + tokens[i];  // names may contain spaces
    const auto found = intrinsics.find(camera_id);
    if (found == intrinsics.end())
      throw InputError(images_path, where + ": camera id " + std::to_string(camera_id) + " is not in cameras.txt");
    Eigen::Quaterniond rotation(v[0], v[1], v[2], v[3]);
    if (std::abs(rotation.norm() - 1.0) > 1e-3)
      throw InputError(images_path, where + ": quaternion is not normalized (norm " + std::to_string(rotation.norm()) + ")");
    Camera camera;
    camera.width = found->second.width;
    camera.height = found->second.height;
    camera.K = found->second.K;
    camera.dist = found->second.dist;
    camera.rotation = rotation.normalized().toRotationMatrix();
    camera.translation = Eigen::Vector3d(v[4], v[5], v[6]);
    cameras.push_back(camera);
    image_names.push_back(name);
    expect_points = true;
  }
  if (cameras.empty()) throw InputError(images_path, "no images");
  const std::vector<std::string> names = NamesFromImagePaths(image_names, images_path);
  Rig rig;
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    cameras[i].name = names[i];
    rig.cameras.push_back(cameras[i]);
  }
  return rig;
}

}  // namespace importers_internal
}  // namespace confluent
