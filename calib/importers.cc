// Importers of COLMAP, transforms.json, Qualisys, plain-text and OpenCV XML calibrations.

#include "calib/importers.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "calib/easymocap_io.h"
#include "calib/opencv_storage.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Shared helpers.

// Parses a whole token as a finite double; throws InputError naming `what` otherwise.
double ParseNumber(const std::string& token, const std::string& path, const std::string& what) {
  const char* begin = token.c_str();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  if (token.empty() || end != begin + token.size())
    throw InputError(path, what + ": expected a number, got '" + token + "'");
  if (!std::isfinite(value)) throw InputError(path, what + ": value is not finite ('" + token + "')");
  return value;
}

int ParseInt(const std::string& token, const std::string& path, const std::string& what) {
  const double value = ParseNumber(token, path, what);
  if (value != std::round(value) || std::abs(value) > 1e9)
    throw InputError(path, what + ": expected an integer, got '" + token + "'");
  return static_cast<int>(value);
}

std::vector<std::string> SplitWhitespace(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> tokens;
  std::string token;
  while (in >> token) tokens.push_back(token);
  return tokens;
}

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// Camera names must be usable as EasyMocap YAML keys: other characters become '_'.
std::string SanitizeName(const std::string& name) {
  std::string result = name;
  for (char& c : result)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') c = '_';
  return result;
}

// Camera names from image paths: the file stems, or the parent folder names when the stems
// repeat (e.g. "cam01/000000.png"). Throws InputError when neither is unique.
std::vector<std::string> NamesFromImagePaths(const std::vector<std::string>& image_paths, const std::string& path) {
  auto unique = [](const std::vector<std::string>& names) {
    return std::set<std::string>(names.begin(), names.end()).size() == names.size();
  };
  std::vector<std::string> stems, parents;
  for (const auto& image_path : image_paths) {
    const fs::path p(image_path);
    stems.push_back(SanitizeName(p.stem().string()));
    parents.push_back(SanitizeName(p.parent_path().filename().string()));
  }
  if (unique(stems)) return stems;
  if (unique(parents) && std::none_of(parents.begin(), parents.end(), [](const std::string& s) { return s.empty(); }))
    return parents;
  throw InputError(path, "camera names derived from the image names are not unique (one image per camera is expected)");
}

Eigen::Matrix3d IntrinsicMatrix(double fx, double fy, double cx, double cy, double skew = 0.0) {
  Eigen::Matrix3d K;
  K << fx, skew, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  return K;
}

// Rotation nearest to `matrix` (SVD), so that rounding in text files does not fail Check().
// Matrices that are far from a rotation are left alone for Check() to reject.
Eigen::Matrix3d Orthonormalize(const Eigen::Matrix3d& matrix) {
  if ((matrix * matrix.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-3 || matrix.determinant() <= 0)
    return matrix;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(matrix, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

// Size of the first image or video found in `folder`, or false.
bool ProbeMediaSize(const fs::path& folder, int* width, int* height) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) return false;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder, error)) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  for (const auto& file : files) {
    const std::string extension = Lower(file.extension().string());
    if (extension == ".png" || extension == ".jpg" || extension == ".jpeg") {
      const cv::Mat image = cv::imread(file.string(), cv::IMREAD_UNCHANGED);
      if (!image.empty()) {
        *width = image.cols;
        *height = image.rows;
        return true;
      }
    } else if (extension == ".avi" || extension == ".mp4" || extension == ".mov" || extension == ".mkv") {
      cv::VideoCapture capture(file.string());
      if (capture.isOpened()) {
        *width = static_cast<int>(capture.get(cv::CAP_PROP_FRAME_WIDTH));
        *height = static_cast<int>(capture.get(cv::CAP_PROP_FRAME_HEIGHT));
        if (*width > 0 && *height > 0) return true;
      }
    }
  }
  return false;
}

// Fills a missing image size from the options; throws InputError when there is none.
void ApplyDefaultSize(Camera* camera, const ImportOptions& options, const std::string& path) {
  if (camera->width > 0 && camera->height > 0) return;
  if (options.default_width > 0 && options.default_height > 0) {
    camera->width = options.default_width;
    camera->height = options.default_height;
    return;
  }
  throw InputError(path, "camera " + camera->name + ": image size unknown (give --width and --height)");
}

// ---------------------------------------------------------------------------------------------
// COLMAP cameras.txt / images.txt. COLMAP puts the centre of the top-left pixel at (0.5, 0.5);
// confluent puts it at (0, 0), so principal points move by -0.5.

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

// ---------------------------------------------------------------------------------------------
// nerfstudio / Blender transforms.json: camera-to-world 4x4 with OpenGL camera axes (x right,
// y up, z backwards). Like COLMAP, principal points have pixel centres at +0.5.

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

// ---------------------------------------------------------------------------------------------
// Qualisys .qca.txt (XML). Conventions as in Pose2Sim's read_qca (Pagnon et al. 2022):
//   - focalLengthU/V, centerPointU/V are in 1/64 pixel; the principal point is relative to the
//     sensor, so fov_video left/top is subtracted; the image size is the fov_video rectangle;
//   - distortion coefficients are divided by 64 as well (Pose2Sim's convention);
//   - transform x y z is the camera centre in the world (mm); r11..r33 rows give the rotation
//     of a camera frame with y up and z backwards, so cam_from_world = Rx(pi) * R.

struct XmlElement {
  std::map<std::string, std::string> attributes;
  std::string content;  // text between the opening and closing tags (empty when self-closing)
};

// Every <tag ...> element of `text` (not nested in itself), with attributes and content.
std::vector<XmlElement> FindXmlElements(const std::string& text, const std::string& tag) {
  std::vector<XmlElement> elements;
  std::size_t position = 0;
  const std::string open = "<" + tag;
  while ((position = text.find(open, position)) != std::string::npos) {
    const std::size_t after = position + open.size();
    if (after >= text.size() || !(std::isspace(static_cast<unsigned char>(text[after])) || text[after] == '>' ||
                                  text[after] == '/')) {
      position = after;
      continue;
    }
    XmlElement element;
    std::size_t i = after;
    bool self_closing = false;
    while (i < text.size()) {
      while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
      if (i >= text.size()) break;
      if (text[i] == '>') {
        ++i;
        break;
      }
      if (text.compare(i, 2, "/>") == 0) {
        self_closing = true;
        i += 2;
        break;
      }
      const std::size_t name_begin = i;
      while (i < text.size() && text[i] != '=' && !std::isspace(static_cast<unsigned char>(text[i])) &&
             text[i] != '>' && text[i] != '/')
        ++i;
      const std::string name = text.substr(name_begin, i - name_begin);
      while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
      if (i < text.size() && text[i] == '=') {
        ++i;
        while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
        if (i < text.size() && (text[i] == '"' || text[i] == '\'')) {
          const char quote = text[i++];
          const std::size_t value_end = text.find(quote, i);
          if (value_end == std::string::npos) break;
          element.attributes[name] = text.substr(i, value_end - i);
          i = value_end + 1;
        }
      } else if (name.empty()) {
        ++i;  // skip a stray character
      }
    }
    if (!self_closing) {
      const std::size_t close = text.find("</" + tag + ">", i);
      element.content = text.substr(i, close == std::string::npos ? std::string::npos : close - i);
      position = close == std::string::npos ? text.size() : close;
    } else {
      position = i;
    }
    elements.push_back(element);
  }
  return elements;
}

double XmlNumber(const XmlElement& element, const std::string& name, const std::string& path,
                 const std::string& where) {
  const auto found = element.attributes.find(name);
  if (found == element.attributes.end()) throw InputError(path, where + ": missing attribute " + name);
  return ParseNumber(found->second, path, where + " " + name);
}

Rig ReadQualisys(const std::string& path) {
  const std::string text = ReadTextFile(path);
  const std::vector<XmlElement> elements = FindXmlElements(text, "camera");
  if (elements.empty()) throw InputError(path, "no <camera> elements (not a Qualisys .qca.txt file?)");
  // Video cameras only (as Pose2Sim), unless there are none.
  std::vector<const XmlElement*> selected;
  for (const auto& element : elements) {
    const auto model = element.attributes.find("model");
    const std::string name = model == element.attributes.end() ? "" : Lower(model->second);
    if (name.find("video") != std::string::npos || name == "none" || name.empty()) selected.push_back(&element);
  }
  if (selected.empty())
    for (const auto& element : elements) selected.push_back(&element);

  Rig rig;
  int index = 0;
  for (const XmlElement* element : selected) {
    ++index;
    const auto serial = element->attributes.find("serial");
    Camera camera;
    camera.name = SanitizeName(serial != element->attributes.end() && !serial->second.empty()
                                   ? serial->second
                                   : "cam" + std::to_string(index));
    const std::string where = "camera " + camera.name;
    const std::vector<XmlElement> fov = FindXmlElements(element->content, "fov_video");
    const std::vector<XmlElement> transform = FindXmlElements(element->content, "transform");
    const std::vector<XmlElement> intrinsic = FindXmlElements(element->content, "intrinsic");
    if (fov.empty() || transform.empty() || intrinsic.empty())
      throw InputError(path, where + ": needs <fov_video>, <transform> and <intrinsic>");
    const double left = XmlNumber(fov[0], "left", path, where);
    const double top = XmlNumber(fov[0], "top", path, where);
    camera.width = static_cast<int>(std::lround(XmlNumber(fov[0], "right", path, where) - left + 1));
    camera.height = static_cast<int>(std::lround(XmlNumber(fov[0], "bottom", path, where) - top + 1));
    const XmlElement& in = intrinsic[0];
    const double fu = XmlNumber(in, "focalLengthU", path, where) / 64.0;
    const double fv = XmlNumber(in, "focalLengthV", path, where) / 64.0;
    const double cu = XmlNumber(in, "centerPointU", path, where) / 64.0 - left;
    const double cv = XmlNumber(in, "centerPointV", path, where) / 64.0 - top;
    double skew = 0.0;
    if (in.attributes.count("skew")) skew = XmlNumber(in, "skew", path, where) / 64.0;
    camera.K = IntrinsicMatrix(fu, fv, cu, cv, skew);
    // Read before assigning: an exception inside Eigen's comma initializer would abort.
    const double k1 = XmlNumber(in, "radialDistortion1", path, where) / 64.0;
    const double k2 = XmlNumber(in, "radialDistortion2", path, where) / 64.0;
    const double p1 = XmlNumber(in, "tangentalDistortion1", path, where) / 64.0;
    const double p2 = XmlNumber(in, "tangentalDistortion2", path, where) / 64.0;
    camera.dist << k1, k2, p1, p2, 0.0;
    if (in.attributes.count("radialDistortion3")) camera.dist[4] = XmlNumber(in, "radialDistortion3", path, where) / 64.0;
    const XmlElement& tr = transform[0];
    Eigen::Matrix3d rotation;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        rotation(r, c) = XmlNumber(tr, "r" + std::to_string(r + 1) + std::to_string(c + 1), path, where);
    const Eigen::Vector3d center(XmlNumber(tr, "x", path, where), XmlNumber(tr, "y", path, where),
                                 XmlNumber(tr, "z", path, where));
    camera.rotation = Orthonormalize(Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal() * rotation);
    camera.translation = -camera.rotation * center;
    rig.cameras.push_back(camera);
  }
  return rig;
}

// ---------------------------------------------------------------------------------------------
// Plain text (tsinghua_lkB CalibParamsB.txt): blocks of camera index, K (3x3), k1 k2, [R|t]
// (3x4, cam_from_world). Names are "cam" + two-digit index. No image size is stored: it comes
// from the options, else 1024x768 (the size of the dataset this format comes from).

Rig ReadPlainText(const std::string& path, const ImportOptions& options) {
  std::istringstream in(ReadTextFile(path));
  std::vector<std::string> tokens;
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t comment = line.find('#');
    if (comment != std::string::npos) line.resize(comment);
    for (const auto& token : SplitWhitespace(line)) tokens.push_back(token);
  }
  constexpr std::size_t kBlock = 1 + 9 + 2 + 12;
  if (tokens.empty()) throw InputError(path, "no cameras");
  if (tokens.size() % kBlock != 0)
    throw InputError(path, "expected blocks of 24 numbers (index, K 3x3, k1 k2, [R|t] 3x4), got " +
                               std::to_string(tokens.size()) + " numbers");
  Rig rig;
  for (std::size_t block = 0; block < tokens.size() / kBlock; ++block) {
    const std::size_t base = block * kBlock;
    const std::string where = "camera block " + std::to_string(block + 1);
    const int index = ParseInt(tokens[base], path, where + " index");
    char name[32];
    std::snprintf(name, sizeof(name), "cam%02d", index);
    Camera camera;
    camera.name = name;
    const std::string camera_where = "camera " + camera.name;
    for (int i = 0; i < 9; ++i) camera.K(i / 3, i % 3) = ParseNumber(tokens[base + 1 + i], path, camera_where + " K");
    camera.dist[0] = ParseNumber(tokens[base + 10], path, camera_where + " k1");
    camera.dist[1] = ParseNumber(tokens[base + 11], path, camera_where + " k2");
    Eigen::Matrix3d rotation;
    for (int i = 0; i < 12; ++i) {
      const double value = ParseNumber(tokens[base + 12 + i], path, camera_where + " [R|t]");
      if (i % 4 == 3) {
        camera.translation[i / 4] = value;
      } else {
        rotation(i / 4, i % 4) = value;
      }
    }
    camera.rotation = Orthonormalize(rotation);
    camera.width = options.default_width > 0 ? options.default_width : 1024;
    camera.height = options.default_height > 0 ? options.default_height : 768;
    rig.cameras.push_back(camera);
  }
  return rig;
}

// ---------------------------------------------------------------------------------------------
// OpenCV FileStorage XML/YAML with CameraMatrix, DistortionCoeffs and rvec/tvec (or Rotation /
// Translation, as in utrecht_4cam config.xml). A directory is read as one camera per
// sub-folder (named after it, using config.xml or the first file with extrinsics) plus one
// per calibration file directly inside it (named after the file stem).

cv::FileNode FirstNode(const cv::FileStorage& storage, std::initializer_list<const char*> names) {
  for (const char* name : names) {
    const cv::FileNode node = storage[name];
    if (!node.isNone()) return node;
  }
  return cv::FileNode();
}

bool ReadCvMatrix(const cv::FileNode& node, const std::string& path, const std::string& what, Eigen::MatrixXd* matrix) {
  if (node.empty() || node.isNone()) return false;
  // OpenCV allocates rows x cols before it looks at the data: refuse absurd sizes first.
  if (node.isMap()) {
    const cv::FileNode rows = node["rows"], cols = node["cols"];
    if (!rows.isInt() || !cols.isInt() || static_cast<int>(rows) < 0 || static_cast<int>(cols) < 0 ||
        static_cast<long long>(static_cast<int>(rows)) * static_cast<int>(cols) > 1024)
      throw InputError(path, what + ": not a small numeric matrix (rows and cols must be integers, at most 1024 values)");
  }
  cv::Mat mat;
  try {
    node >> mat;
  } catch (const cv::Exception& exception) {
    throw InputError(path, what + ": not a numeric matrix (" + exception.err + ")");
  } catch (const std::exception& exception) {
    throw InputError(path, what + ": not a numeric matrix (" + exception.what() + ")");
  }
  if (mat.empty()) throw InputError(path, what + ": not a numeric matrix");
  mat.convertTo(mat, CV_64F);
  matrix->resize(mat.rows, mat.cols * mat.channels());
  mat = mat.reshape(1);
  for (int r = 0; r < mat.rows; ++r)
    for (int c = 0; c < mat.cols; ++c) (*matrix)(r, c) = mat.at<double>(r, c);
  if (!matrix->allFinite()) throw InputError(path, what + " contains NaN or infinite values");
  return true;
}

// True when the file holds a camera matrix and extrinsics.
bool HasCvExtrinsics(const std::string& path) {
  try {
    cv::FileStorage storage;
    OpenFileStorage(path, "OpenCV XML/YAML", &storage);
    return !FirstNode(storage, {"CameraMatrix", "camera_matrix", "K"}).isNone() &&
           !FirstNode(storage, {"rvec", "Rotation", "R", "rotation"}).isNone();
  } catch (const std::exception&) {  // InputError, or cv::Exception from a lookup
    return false;
  }
}

Camera ReadOpenCvCamera(const std::string& path, const std::string& name, const ImportOptions& options) {
  cv::FileStorage storage;
  OpenFileStorage(path, "OpenCV XML/YAML", &storage);
  Camera camera;
  camera.name = SanitizeName(name);
  const std::string where = "camera " + camera.name;
  Eigen::MatrixXd matrix;
  if (!ReadCvMatrix(FirstNode(storage, {"CameraMatrix", "camera_matrix", "K", "cameraMatrix"}), path, where + " CameraMatrix",
                    &matrix))
    throw InputError(path, where + ": missing CameraMatrix");
  if (matrix.rows() != 3 || matrix.cols() != 3) throw InputError(path, where + ": CameraMatrix must be 3x3");
  camera.K = matrix;
  if (ReadCvMatrix(FirstNode(storage, {"DistortionCoeffs", "distortion_coefficients", "dist", "D", "distCoeffs"}),
                   path, where + " DistortionCoeffs", &matrix)) {
    if (matrix.rows() != 1 && matrix.cols() != 1) throw InputError(path, where + ": DistortionCoeffs must be a vector");
    const int count = static_cast<int>(matrix.size());
    for (int i = 0; i < count; ++i) {
      if (i < 5) {
        camera.dist[i] = matrix(i);
      } else if (matrix(i) != 0.0) {
        throw InputError(path, where + ": unsupported distortion model with " + std::to_string(count) +
                                   " coefficients (only k1 k2 p1 p2 k3)");
      }
    }
  }
  if (!ReadCvMatrix(FirstNode(storage, {"rvec", "Rotation", "R", "rotation"}), path, where + " rotation", &matrix))
    throw InputError(path, where + ": missing rvec (or Rotation)");
  if (matrix.size() == 3) {
    const Eigen::Vector3d rodrigues(matrix(0), matrix(1), matrix(2));
    const double angle = rodrigues.norm();
    camera.rotation =
        angle > 0.0 ? Eigen::AngleAxisd(angle, rodrigues / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  } else if (matrix.rows() == 3 && matrix.cols() == 3) {
    camera.rotation = Orthonormalize(matrix);
  } else {
    throw InputError(path, where + ": rotation must be a Rodrigues 3-vector or a 3x3 matrix");
  }
  if (!ReadCvMatrix(FirstNode(storage, {"tvec", "Translation", "T", "translation"}), path, where + " translation",
                    &matrix))
    throw InputError(path, where + ": missing tvec (or Translation)");
  if (matrix.size() != 3) throw InputError(path, where + ": translation must have 3 values");
  camera.translation = Eigen::Vector3d(matrix(0), matrix(1), matrix(2));
  // Image size: stored, else the options, else the first image or video beside the file.
  const cv::FileNode width = FirstNode(storage, {"image_width", "ImageWidth", "width"});
  const cv::FileNode height = FirstNode(storage, {"image_height", "ImageHeight", "height"});
  if ((width.isInt() || width.isReal()) && (height.isInt() || height.isReal())) {
    for (const cv::FileNode& size : {width, height})
      if (!(static_cast<double>(size) > 0.0 && static_cast<double>(size) <= 1e6))
        throw InputError(path, where + ": image size must be between 1 and 1000000 pixels");
    camera.width = static_cast<int>(static_cast<double>(width));
    camera.height = static_cast<int>(static_cast<double>(height));
  } else if (options.default_width > 0 && options.default_height > 0) {
    camera.width = options.default_width;
    camera.height = options.default_height;
  } else if (!ProbeMediaSize(fs::path(path).parent_path(), &camera.width, &camera.height)) {
    ApplyDefaultSize(&camera, options, path);
  }
  return camera;
}

Rig ReadOpenCvXml(const std::string& input_path, const ImportOptions& options) {
  std::error_code error;
  Rig rig;
  if (!fs::is_directory(input_path, error)) {
    if (!fs::is_regular_file(input_path, error)) throw InputError(input_path, "file not found");
    const fs::path p(input_path);
    // A generic file name ("config.xml") is named after its folder.
    const std::string stem = p.stem().string();
    const bool generic = stem == "config" || stem == "calibration" || stem == "camera" || stem == "extrinsics";
    const std::string parent = fs::absolute(p, error).parent_path().filename().string();
    rig.cameras.push_back(ReadOpenCvCamera(input_path, generic && !parent.empty() ? parent : stem, options));
    return rig;
  }
  std::vector<fs::path> entries;
  for (const auto& entry : fs::directory_iterator(input_path, error)) entries.push_back(entry.path());
  std::sort(entries.begin(), entries.end());
  auto is_calibration_file = [](const fs::path& p) {
    const std::string extension = Lower(p.extension().string());
    return extension == ".xml" || extension == ".yml" || extension == ".yaml";
  };
  for (const auto& entry : entries) {
    if (fs::is_directory(entry, error)) {
      std::vector<fs::path> files;
      for (const auto& file : fs::directory_iterator(entry, error))
        if (is_calibration_file(file.path())) files.push_back(file.path());
      std::sort(files.begin(), files.end(), [](const fs::path& a, const fs::path& b) {
        // config.xml first, then by name.
        const bool a_config = a.stem() == "config", b_config = b.stem() == "config";
        return a_config != b_config ? a_config : a < b;
      });
      for (const auto& file : files) {
        if (HasCvExtrinsics(file.string())) {
          rig.cameras.push_back(ReadOpenCvCamera(file.string(), entry.filename().string(), options));
          break;
        }
      }
    } else if (is_calibration_file(entry) && HasCvExtrinsics(entry.string())) {
      rig.cameras.push_back(ReadOpenCvCamera(entry.string(), entry.stem().string(), options));
    }
  }
  if (rig.cameras.empty())
    throw InputError(input_path, "no OpenCV calibration files with CameraMatrix and rvec/tvec found");
  return rig;
}

Rig ReadEasyMocapInput(const std::string& input_path) {
  std::error_code error;
  fs::path folder(input_path);
  if (!fs::is_directory(folder, error)) folder = folder.parent_path();
  return ReadEasyMocap((folder / "intri.yml").string(), (folder / "extri.yml").string());
}

}  // namespace

CalibFormat ParseCalibFormat(const std::string& name) {
  const std::string lower = Lower(name);
  if (lower == "easymocap") return CalibFormat::kEasyMocap;
  if (lower == "colmap") return CalibFormat::kColmap;
  if (lower == "transforms" || lower == "nerfstudio" || lower == "blender") return CalibFormat::kTransformsJson;
  if (lower == "qualisys" || lower == "qca") return CalibFormat::kQualisys;
  if (lower == "plain") return CalibFormat::kPlainText;
  if (lower == "opencv-xml" || lower == "opencv") return CalibFormat::kOpenCvXml;
  throw UsageError("unknown calibration format '" + name +
                   "' (accepted: easymocap, colmap, transforms, qualisys, plain, opencv-xml)");
}

Eigen::Matrix3d RotationToZUp(const std::string& up_axis) {
  Eigen::Matrix3d rotation;
  const std::string axis = !up_axis.empty() && up_axis[0] != '+' && up_axis[0] != '-' ? "+" + up_axis : up_axis;
  if (axis == "+z") {
    rotation.setIdentity();
  } else if (axis == "-z") {
    rotation << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  } else if (axis == "+y") {
    rotation << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  } else if (axis == "-y") {
    rotation << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  } else if (axis == "+x") {
    rotation << 0, 0, -1, 0, 1, 0, 1, 0, 0;
  } else if (axis == "-x") {
    rotation << 0, 0, 1, 0, 1, 0, -1, 0, 0;
  } else {
    throw UsageError("unknown up axis '" + up_axis + "' (accepted: +z, -z, +y, -y, +x, -x)");
  }
  return rotation;
}

Rig ImportCalibration(CalibFormat format, const std::string& input_path, const ImportOptions& options) {
  if (options.metres_per_unit < 0.0 || !std::isfinite(options.metres_per_unit))
    throw UsageError("metres per unit must be positive");
  const Eigen::Matrix3d up = RotationToZUp(options.up_axis);
  std::error_code error;
  if (!fs::exists(input_path, error)) throw InputError(input_path, "not found");
  Rig rig;
  double default_metres_per_unit = 1.0;
  switch (format) {
    case CalibFormat::kEasyMocap:
      rig = ReadEasyMocapInput(input_path);
      break;
    case CalibFormat::kColmap:
      rig = ReadColmap(input_path);
      break;
    case CalibFormat::kTransformsJson:
      rig = ReadTransformsJson(input_path, options);
      break;
    case CalibFormat::kQualisys:
      rig = ReadQualisys(input_path);
      default_metres_per_unit = 0.001;
      break;
    case CalibFormat::kPlainText:
      rig = ReadPlainText(input_path, options);
      break;
    case CalibFormat::kOpenCvXml:
      rig = ReadOpenCvXml(input_path, options);
      default_metres_per_unit = 0.001;
      break;
  }
  const double metres_per_unit = options.metres_per_unit > 0.0 ? options.metres_per_unit : default_metres_per_unit;
  rig.Check(input_path);
  if (metres_per_unit != 1.0 || !up.isIdentity()) TransformWorld(&rig, up, metres_per_unit);
  rig.Check(input_path);
  return rig;
}

}  // namespace confluent
