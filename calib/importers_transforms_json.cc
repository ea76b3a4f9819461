// nerfstudio / Blender transforms.json: camera-to-world 4x4 with OpenGL camera axes (x right,
// y up, z backwards). Like COLMAP, principal points have pixel centres at +0.5.

#include <cmath>
#include <fstream>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "calib/importers_internal.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace importers_internal {

namespace {

using Json = nlohmann::json;

// A number from `frame` or, when absent there, from `root`; false when in neither.
bool JsonNumber(const Json& frame, const Json& root, const char* key, const std::string& path, double* value) {
  const Json* source = frame.contains(key) ? &frame : root.contains(key) ? &root : nullptr;
  if (source == nullptr || (*source)[key].is_null()) return false;
  if (!(*source)[key].is_number()) throw InputError(path, std::string("'") + key + "' must be a number");
  *value = (*source)[key].get<double>();
  if (!std::isfinite(*value)) throw InputError(path, std::string("'") + key + "' is not finite");
  return true;
}

}  // namespace

Rig ReadTransformsJson(const std::string& input_path, const ImportOptions& options) {
  std::string path = input_path;
  std::error_code error;
  if (fs::is_directory(path, error)) path = (fs::path(path) / "transforms.json").string();
  Json root;
  try {
    root = Json::parse(ReadTextFile(path));
  } catch (const Json::exception& exception) {
    throw InputError(path, std::string("invalid JSON: ") + exception.what());
  }
  if (!root.is_object() || !root.contains("frames") || !root["frames"].is_array() || root["frames"].empty())
    throw InputError(path, "expected an object with a non-empty 'frames' list");
  if (root.contains("camera_model") && root["camera_model"].is_string()) {
    const std::string model = root["camera_model"].get<std::string>();
    if (model != "OPENCV" && model != "PINHOLE" && model != "SIMPLE_PINHOLE")
      throw InputError(path, "unsupported camera_model " + model + " (supported: OPENCV, PINHOLE)");
  }
  const fs::path folder = fs::path(path).parent_path();
  Rig rig;
  std::vector<std::string> file_paths;
  int index = 0;
  for (const Json& frame : root["frames"]) {
    const std::string where = "frame " + std::to_string(index++);
    if (!frame.is_object() || !frame.contains("transform_matrix"))
      throw InputError(path, where + ": missing 'transform_matrix'");
    const Json& matrix = frame["transform_matrix"];
    if (!matrix.is_array() || matrix.size() < 3)
      throw InputError(path, where + ": 'transform_matrix' must be a 4x4 list of rows");
    Eigen::Matrix4d world_from_camera_gl = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r) {
      if (!matrix[r].is_array() || matrix[r].size() != 4)
        throw InputError(path, where + ": 'transform_matrix' must be a 4x4 list of rows");
      for (int c = 0; c < 4; ++c) {
        if (!matrix[r][c].is_number()) throw InputError(path, where + ": 'transform_matrix' has a non-numeric entry");
        world_from_camera_gl(r, c) = matrix[r][c].get<double>();
      }
    }
    if (!world_from_camera_gl.allFinite()) throw InputError(path, where + ": 'transform_matrix' is not finite");
    // OpenGL camera axes -> OpenCV camera axes: flip y and z.
    const Eigen::Matrix3d world_from_camera =
        world_from_camera_gl.topLeftCorner<3, 3>() * Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
    const Eigen::Vector3d center = world_from_camera_gl.topRightCorner<3, 1>();

    Camera camera;
    camera.rotation = Orthonormalize(world_from_camera.transpose());
    camera.translation = -camera.rotation * center;
    double value = 0.0;
    if (JsonNumber(frame, root, "w", path, &value)) camera.width = static_cast<int>(std::lround(value));
    if (JsonNumber(frame, root, "h", path, &value)) camera.height = static_cast<int>(std::lround(value));
    const std::string file_path = frame.contains("file_path") && frame["file_path"].is_string()
                                      ? frame["file_path"].get<std::string>()
                                      : "camera" + std::to_string(index - 1);
    file_paths.push_back(file_path);
    if (camera.width <= 0 || camera.height <= 0) {
      camera.width = options.default_width;
      camera.height = options.default_height;
    }
    if (camera.width <= 0 || camera.height <= 0) {
      // Blender datasets store no size: read the image (its path may lack the extension).
      for (const std::string extension : {"", ".png", ".jpg", ".jpeg"}) {
        const fs::path image_path = folder / (file_path + extension);
        if (!fs::is_regular_file(image_path, error)) continue;
        const cv::Mat image = cv::imread(image_path.string(), cv::IMREAD_UNCHANGED);
        if (!image.empty()) {
          camera.width = image.cols;
          camera.height = image.rows;
          break;
        }
      }
    }
    if (camera.width <= 0 || camera.height <= 0)
      throw InputError(path, where + ": image size unknown (no 'w'/'h', image not found; give --width and --height)");
    double fx = 0.0, fy = 0.0, cx = 0.5 * camera.width, cy = 0.5 * camera.height;
    if (!JsonNumber(frame, root, "fl_x", path, &fx)) {
      double angle_x = 0.0;
      if (!JsonNumber(frame, root, "camera_angle_x", path, &angle_x))
        throw InputError(path, where + ": no focal length ('fl_x' or 'camera_angle_x')");
      fx = 0.5 * camera.width / std::tan(0.5 * angle_x);
    }
    if (!JsonNumber(frame, root, "fl_y", path, &fy)) {
      double angle_y = 0.0;
      fy = JsonNumber(frame, root, "camera_angle_y", path, &angle_y) ? 0.5 * camera.height / std::tan(0.5 * angle_y)
                                                                      : fx;
    }
    JsonNumber(frame, root, "cx", path, &cx);
    JsonNumber(frame, root, "cy", path, &cy);
    camera.K = IntrinsicMatrix(fx, fy, cx - 0.5, cy - 0.5);
    const char* keys[] = {"k1", "k2", "p1", "p2", "k3"};
    for (int i = 0; i < 5; ++i) {
      if (JsonNumber(frame, root, keys[i], path, &value)) camera.dist[i] = value;
    }
    if (JsonNumber(frame, root, "k4", path, &value) && value != 0.0)
      throw InputError(path, where + ": unsupported distortion model (non-zero k4; only k1 k2 p1 p2 k3)");
    rig.cameras.push_back(camera);
  }
  const std::vector<std::string> names = NamesFromImagePaths(file_paths, path);
  for (std::size_t i = 0; i < names.size(); ++i) rig.cameras[i].name = names[i];
  return rig;
}

}  // namespace importers_internal
}  // namespace confluent
