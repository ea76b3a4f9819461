// Importers of COLMAP, transforms.json, Qualisys, plain-text and OpenCV XML calibrations: the
// helpers they share and the dispatch; each format's reader is in its importers_*.cc.

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
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "calib/easymocap_io.h"
#include "calib/importers_internal.h"
#include "calib/opencv_storage.h"
#include "calib/pose2sim_io.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace importers_internal {

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

Eigen::Matrix3d IntrinsicMatrix(double fx, double fy, double cx, double cy, double skew) {
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

}  // namespace importers_internal

namespace {

using namespace importers_internal;

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
  if (lower == "pose2sim" || lower == "toml") return CalibFormat::kPose2Sim;
  throw UsageError("unknown calibration format '" + name +
                   "' (accepted: easymocap, colmap, transforms, qualisys, plain, opencv-xml, pose2sim)");
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
    case CalibFormat::kPose2Sim:
      rig = ReadPose2SimToml(input_path);
      break;
  }
  const double metres_per_unit = options.metres_per_unit > 0.0 ? options.metres_per_unit : default_metres_per_unit;
  rig.Check(input_path);
  if (metres_per_unit != 1.0 || !up.isIdentity()) TransformWorld(&rig, up, metres_per_unit);
  rig.Check(input_path);
  return rig;
}

}  // namespace confluent
