// EasyMocap intri.yml / extri.yml reading and writing through cv::FileStorage.

#include "calib/easymocap_io.h"

#include <cmath>
#include <filesystem>
#include <sstream>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "calib/opencv_storage.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace {

// An opened cv::FileStorage with its path, for error messages.
struct YamlFile {
  std::string path;
  cv::FileStorage storage;
};

void OpenYaml(const std::string& path, YamlFile* file) {
  file->path = path;
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) throw InputError(path, "file not found");
  OpenFileStorage(path, "OpenCV YAML", &file->storage);
}

std::string NodeText(const cv::FileNode& node) {
  if (node.isString()) return "'" + static_cast<std::string>(node) + "'";
  if (node.isSeq()) return "a list";
  if (node.isMap()) return "a map";
  return "an empty value";
}

// Reads a numeric scalar entry; throws InputError when it is not a finite number.
double ReadNumber(const cv::FileNode& node, const std::string& path, const std::string& camera,
                  const std::string& key) {
  if (node.isInt()) return static_cast<int>(node);
  if (node.isReal()) {
    const double value = static_cast<double>(node);
    if (!std::isfinite(value)) throw InputError(path, "camera " + camera + ": " + key + " is not finite (NaN or inf)");
    return value;
  }
  throw InputError(path, "camera " + camera + ": " + key + " must be numeric, got " + NodeText(node));
}

// Reads an opencv-matrix (rows, cols, data) or a plain list of numbers (as a column).
// Returns false when the entry is absent. Throws InputError on a non-numeric or non-finite
// value or a size mismatch.
bool ReadMatrix(const cv::FileNode& node, const std::string& path, const std::string& camera,
                const std::string& key, Eigen::MatrixXd* matrix) {
  if (node.isNone()) return false;
  cv::FileNode data;
  int rows = 0, cols = 1;
  if (node.isMap()) {
    const cv::FileNode rows_node = node["rows"], cols_node = node["cols"];
    data = node["data"];
    if (!rows_node.isInt() || !cols_node.isInt() || !(data.isSeq() || data.isInt() || data.isReal()))
      throw InputError(path, "camera " + camera + ": " + key + " is not an OpenCV matrix (rows, cols, data)");
    rows = static_cast<int>(rows_node);
    cols = static_cast<int>(cols_node);
  } else if (node.isSeq()) {
    data = node;
    rows = static_cast<int>(node.size());
  } else if (node.isInt() || node.isReal()) {
    data = node;
    rows = 1;
  } else {
    throw InputError(path, "camera " + camera + ": " + key + " must be numeric (a number or matrix), got " + NodeText(node));
  }
  const int count = data.isSeq() ? static_cast<int>(data.size()) : 1;
  if (rows < 0 || cols < 0 || count != static_cast<long long>(rows) * cols) {
    std::ostringstream out;
    out << "camera " << camera << ": " << key << " has " << count << " values for a " << rows << "x" << cols
        << " matrix";
    throw InputError(path, out.str());
  }
  matrix->resize(rows, cols);
  if (!data.isSeq()) {
    (*matrix)(0, 0) = ReadNumber(data, path, camera, key);
    return true;
  }
  int index = 0;
  for (auto it = data.begin(); it != data.end(); ++it, ++index)
    (*matrix)(index / cols, index % cols) = ReadNumber(*it, path, camera, key);
  return true;
}

Eigen::MatrixXd RequireMatrix(const cv::FileNode& node, const std::string& path, const std::string& camera,
                              const std::string& key, int rows, int cols) {
  Eigen::MatrixXd matrix;
  if (!ReadMatrix(node, path, camera, key, &matrix)) throw InputError(path, "camera " + camera + ": missing " + key);
  const bool vector_ok = (rows == 1 || cols == 1) && matrix.size() == rows * cols &&
                         (matrix.rows() == 1 || matrix.cols() == 1);
  if (!vector_ok && (matrix.rows() != rows || matrix.cols() != cols)) {
    std::ostringstream out;
    out << "camera " << camera << ": " << key << " must be " << rows << "x" << cols << ", got " << matrix.rows()
        << "x" << matrix.cols();
    throw InputError(path, out.str());
  }
  if (vector_ok) {
    Eigen::MatrixXd reshaped(rows, cols);
    for (int i = 0; i < rows * cols; ++i) reshaped(i / cols, i % cols) = matrix(i);
    return reshaped;
  }
  return matrix;
}

int RequireInt(const cv::FileNode& node, const std::string& path, const std::string& camera, const std::string& key) {
  Eigen::MatrixXd matrix;
  if (!ReadMatrix(node, path, camera, key, &matrix)) throw InputError(path, "camera " + camera + ": missing " + key);
  if (matrix.size() != 1) throw InputError(path, "camera " + camera + ": " + key + " must be a single number");
  const double value = matrix(0);
  if (value != std::round(value) || value <= 0 || value > 1e6)
    throw InputError(path, "camera " + camera + ": " + key + " must be a positive integer");
  return static_cast<int>(value);
}

// The camera names listed under `names`, or an empty list when the entry is absent.
std::vector<std::string> ReadNames(const YamlFile& file) {
  const cv::FileNode node = file.storage["names"];
  std::vector<std::string> names;
  if (node.isNone()) return names;
  if (!node.isSeq()) throw InputError(file.path, "'names' must be a list of camera names");
  for (auto it = node.begin(); it != node.end(); ++it) {
    const cv::FileNode name = *it;
    if (name.isString()) {
      names.push_back(static_cast<std::string>(name));
    } else if (name.isInt()) {
      names.push_back(std::to_string(static_cast<int>(name)));
    } else {
      throw InputError(file.path, "'names' must be a list of camera names, got " + NodeText(name));
    }
  }
  return names;
}

// Checks that `rotation` is a proper rotation (orthonormal, det +1).
void CheckRotation(const Eigen::Matrix3d& rotation, const std::string& path, const std::string& camera,
                   const std::string& key) {
  const double orthogonality_error = (rotation * rotation.transpose() - Eigen::Matrix3d::Identity()).norm();
  const double det = rotation.determinant();
  if (orthogonality_error > 1e-6 || std::abs(det - 1.0) > 1e-6) {
    std::ostringstream out;
    out << "camera " << camera << ": " << key << " is not a rotation (|R R^T - I| = " << orthogonality_error
        << ", det = " << det << ")";
    throw InputError(path, out.str());
  }
}

// Distortion coefficients of any length as k1 k2 p1 p2 k3. Longer OpenCV models (8, 12, 14
// coefficients) are accepted only when the extra coefficients are all zero.
Vector5d DistortionFromCoefficients(const Eigen::VectorXd& coefficients, const std::string& path,
                                    const std::string& camera) {
  Vector5d dist = Vector5d::Zero();
  const int count = static_cast<int>(coefficients.size());
  for (int i = 0; i < count; ++i) {
    if (i < 5) {
      dist[i] = coefficients[i];
    } else if (coefficients[i] != 0.0) {
      std::ostringstream out;
      out << "camera " << camera << ": unsupported distortion model with " << count
          << " coefficients (only k1 k2 p1 p2 k3 are supported; coefficient " << i + 1 << " is " << coefficients[i]
          << ")";
      throw InputError(path, out.str());
    }
  }
  return dist;
}

}  // namespace

Rig ReadEasyMocap(const std::string& intri_path, const std::string& extri_path) {
  YamlFile intri, extri;
  OpenYaml(intri_path, &intri);
  OpenYaml(extri_path, &extri);
  std::vector<std::string> names = ReadNames(intri);
  if (names.empty()) names = ReadNames(extri);
  if (names.empty()) throw InputError(intri_path, "no camera names (missing or empty 'names' list)");

  Rig rig;
  try {
    for (const std::string& name : names) {
      Camera camera;
      camera.name = name;
      const std::string k_key = "K_" + name;
      camera.K = RequireMatrix(intri.storage[k_key], intri_path, name, k_key, 3, 3);
      Eigen::MatrixXd coefficients;
      std::string dist_key = "dist_" + name;
      if (intri.storage[dist_key].isNone() && !intri.storage["D_" + name].isNone()) dist_key = "D_" + name;
      if (ReadMatrix(intri.storage[dist_key], intri_path, name, dist_key, &coefficients)) {
        if (coefficients.rows() != 1 && coefficients.cols() != 1 && coefficients.size() != 0)
          throw InputError(intri_path, "camera " + name + ": " + dist_key + " must be a row or column vector");
        camera.dist = DistortionFromCoefficients(
            Eigen::Map<const Eigen::VectorXd>(coefficients.data(), coefficients.size()), intri_path, name);
      }
      camera.height = RequireInt(intri.storage["H_" + name], intri_path, name, "H_" + name);
      camera.width = RequireInt(intri.storage["W_" + name], intri_path, name, "W_" + name);

      const std::string rot_key = "Rot_" + name, r_key = "R_" + name, t_key = "T_" + name;
      if (!extri.storage[rot_key].isNone()) {
        camera.rotation = RequireMatrix(extri.storage[rot_key], extri_path, name, rot_key, 3, 3);
        CheckRotation(camera.rotation, extri_path, name, rot_key);
      } else if (!extri.storage[r_key].isNone()) {
        const Eigen::Vector3d rodrigues = RequireMatrix(extri.storage[r_key], extri_path, name, r_key, 3, 1);
        const double angle = rodrigues.norm();
        camera.rotation = angle > 0.0 ? Eigen::AngleAxisd(angle, rodrigues / angle).toRotationMatrix()
                                      : Eigen::Matrix3d::Identity();
      } else {
        throw InputError(extri_path, "camera " + name + ": missing " + rot_key + " or " + r_key);
      }
      camera.translation = RequireMatrix(extri.storage[t_key], extri_path, name, t_key, 3, 1);
      camera.Check(intri_path);
      rig.cameras.push_back(camera);
    }
  } catch (const cv::Exception& exception) {
    throw InputError(intri_path, "cannot read OpenCV YAML: " + exception.err);
  }
  rig.Check(intri_path);
  return rig;
}

namespace {

cv::Mat ToCvMat(const Eigen::MatrixXd& matrix) {
  cv::Mat result(static_cast<int>(matrix.rows()), static_cast<int>(matrix.cols()), CV_64F);
  for (int r = 0; r < matrix.rows(); ++r)
    for (int c = 0; c < matrix.cols(); ++c) result.at<double>(r, c) = matrix(r, c);
  return result;
}

// True when "K_<name>" is a valid cv::FileStorage key.
bool IsValidKeySuffix(const std::string& name) {
  if (name.empty()) return false;
  for (const char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') return false;
  return true;
}

void WriteNames(cv::FileStorage* storage, const Rig& rig) {
  *storage << "names" << "[";
  for (const auto& camera : rig.cameras) *storage << camera.name;
  *storage << "]";
}

}  // namespace

void WriteEasyMocap(const Rig& rig, const std::string& dir) {
  const std::string intri_path = dir + "/intri.yml";
  const std::string extri_path = dir + "/extri.yml";
  for (const auto& camera : rig.cameras)
    if (!IsValidKeySuffix(camera.name))
      throw OutputError(intri_path, "camera name '" + camera.name +
                                        "' cannot be written as a YAML key (use letters, digits, '_' or '-')");
  std::string intri_text, extri_text;
  try {
    cv::FileStorage intri(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
    WriteNames(&intri, rig);
    for (const auto& camera : rig.cameras) {
      intri << "K_" + camera.name << ToCvMat(camera.K);
      intri << "dist_" + camera.name << ToCvMat(camera.dist.transpose());
      intri << "H_" + camera.name << camera.height;
      intri << "W_" + camera.name << camera.width;
    }
    intri_text = intri.releaseAndGetString();

    cv::FileStorage extri(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
    WriteNames(&extri, rig);
    for (const auto& camera : rig.cameras) {
      const Eigen::AngleAxisd angle_axis(camera.rotation);
      const Eigen::Vector3d rodrigues = angle_axis.angle() * angle_axis.axis();
      extri << "R_" + camera.name << ToCvMat(rodrigues);
      extri << "Rot_" + camera.name << ToCvMat(camera.rotation);
      extri << "T_" + camera.name << ToCvMat(camera.translation);
    }
    extri_text = extri.releaseAndGetString();
  } catch (const cv::Exception& exception) {
    throw OutputError(intri_path, "cannot write OpenCV YAML: " + exception.err);
  }
  WriteTextFile(intri_path, intri_text);
  WriteTextFile(extri_path, extri_text);
}

}  // namespace confluent
