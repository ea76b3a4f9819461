// OpenCV FileStorage XML/YAML with CameraMatrix, DistortionCoeffs and rvec/tvec (or Rotation /
// Translation, as in utrecht_4cam config.xml). A directory is read as one camera per
// sub-folder (named after it, using config.xml or the first file with extrinsics) plus one
// per calibration file directly inside it (named after the file stem).

#include <map>
#include <set>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "calib/opencv_storage.h"
#include "calib/importers_internal.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace importers_internal {

namespace {

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

}  // namespace

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

}  // namespace importers_internal
}  // namespace confluent
