// Pose2Sim TOML calibrations: parsed with toml++ (Debian's libtomlplusplus), written by hand in
// Pose2Sim's own layout.

#include "calib/pose2sim_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <toml++/toml.h>

#include "calib/importers_internal.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace {

using importers_internal::Orthonormalize;

// A finite number (TOML integer or float) at `node`, else InputError naming `what`.
double Number(const toml::node* node, const std::string& path, const std::string& what) {
  const std::optional<double> value = node ? node->value<double>() : std::nullopt;
  if (!value) throw InputError(path, what + ": expected a number");
  if (!std::isfinite(*value)) throw InputError(path, what + ": value is not finite");
  return *value;
}

// The numbers of a flat array with `min_size`..`max_size` entries.
std::vector<double> NumberArray(const toml::table& camera, const char* key, std::size_t min_size, std::size_t max_size,
                                const std::string& path, const std::string& where) {
  const toml::array* array = camera[key].as_array();
  const std::string what = where + " '" + key + "'";
  if (!array) throw InputError(path, what + ": missing or not an array");
  if (array->size() < min_size || array->size() > max_size) {
    const std::string expected =
        min_size == max_size ? std::to_string(min_size) : std::to_string(min_size) + " to " + std::to_string(max_size);
    throw InputError(path, what + ": expected " + expected + " numbers, got " + std::to_string(array->size()));
  }
  std::vector<double> values;
  for (std::size_t i = 0; i < array->size(); ++i) values.push_back(Number(array->get(i), path, what));
  return values;
}

// OpenCV's Rodrigues vector (axis times angle) and back. Eigen's angle-axis conversions go
// through a quaternion, which stays exact near a half turn, where cv::Rodrigues loses 1e-8.
Eigen::Matrix3d RotationFromRodrigues(const Eigen::Vector3d& rvec) {
  const double angle = rvec.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, rvec / angle).toRotationMatrix();
}

Eigen::Vector3d RodriguesFromRotation(const Eigen::Matrix3d& rotation) {
  const Eigen::AngleAxisd angle_axis(rotation);
  return angle_axis.angle() * angle_axis.axis();
}

Camera ReadCamera(const std::string& table_name, const toml::table& table, const std::string& path) {
  const std::string where = "camera [" + table_name + "]";
  Camera camera;
  const std::optional<std::string> name = table["name"].value<std::string>();
  camera.name = importers_internal::SanitizeName(name && !name->empty() ? *name : table_name);

  const std::vector<double> size = NumberArray(table, "size", 2, 2, path, where);
  if (size[0] != std::round(size[0]) || size[1] != std::round(size[1]) || size[0] < 1 || size[1] < 1 ||
      size[0] > 1e6 || size[1] > 1e6)
    throw InputError(path, where + " 'size': expected a positive whole width and height");
  camera.width = static_cast<int>(size[0]);
  camera.height = static_cast<int>(size[1]);

  const toml::array* rows = table["matrix"].as_array();
  if (!rows || rows->size() != 3) throw InputError(path, where + " 'matrix': expected 3 rows of 3 numbers");
  for (int r = 0; r < 3; ++r) {
    const toml::array* row = rows->get(r)->as_array();
    if (!row || row->size() != 3) throw InputError(path, where + " 'matrix': expected 3 rows of 3 numbers");
    for (int c = 0; c < 3; ++c) camera.K(r, c) = Number(row->get(c), path, where + " 'matrix'");
  }

  const std::vector<double> distortions = NumberArray(table, "distortions", 4, 5, path, where);
  for (std::size_t i = 0; i < distortions.size(); ++i) camera.dist[static_cast<int>(i)] = distortions[i];

  if (table["fisheye"].value<bool>().value_or(false))
    throw InputError(path, where + " is a fisheye camera; only the pinhole model (k1 k2 p1 p2 k3) is supported");

  const std::vector<double> rvec = NumberArray(table, "rotation", 3, 3, path, where);
  camera.rotation = Orthonormalize(RotationFromRodrigues(Eigen::Vector3d(rvec[0], rvec[1], rvec[2])));

  const std::vector<double> translation = NumberArray(table, "translation", 3, 3, path, where);
  camera.translation = Eigen::Vector3d(translation[0], translation[1], translation[2]);
  return camera;
}

// 17 significant digits: the double comes back unchanged.
std::string Exact(double value) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.17g", value);
  std::string result = text;
  if (result.find_first_of(".eEn") == std::string::npos) result += ".0";  // a TOML float
  return result;
}

std::string List(const std::vector<double>& values) {
  std::string text = "[ ";
  for (std::size_t i = 0; i < values.size(); ++i) text += (i ? ", " : "") + Exact(values[i]);
  return text + "]";
}

// Escapes a TOML basic string.
std::string Quoted(const std::string& text) {
  std::string result = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') result += '\\';
    result += c;
  }
  return result + "\"";
}

}  // namespace

Rig ReadPose2SimToml(const std::string& path) {
  const std::string text = ReadTextFile(path);
  toml::table root;
  try {
    root = toml::parse(text, path);
  } catch (const toml::parse_error& error) {
    throw InputError(path, "line " + std::to_string(error.source().begin.line) + ": " +
                               std::string(error.description()));
  }
  // Cameras in the file's order (toml++ keeps tables sorted by key).
  std::vector<std::pair<std::uint32_t, Camera>> cameras;
  for (const auto& [key, node] : root) {
    const toml::table* table = node.as_table();
    if (!table || !table->contains("matrix")) continue;  // [metadata] and the like
    cameras.emplace_back(node.source().begin.line, ReadCamera(std::string(key.str()), *table, path));
  }
  if (cameras.empty()) throw InputError(path, "no camera (no table with a 'matrix')");
  std::stable_sort(cameras.begin(), cameras.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  Rig rig;
  for (auto& entry : cameras) rig.cameras.push_back(std::move(entry.second));
  return rig;
}

void WritePose2SimToml(const Rig& rig, const std::string& path) {
  std::ostringstream out;
  for (const Camera& camera : rig.cameras) {
    const Eigen::Vector3d rvec = RodriguesFromRotation(camera.rotation);
    std::vector<double> distortions(camera.dist.data(), camera.dist.data() + 4);
    if (camera.dist[4] != 0.0) distortions.push_back(camera.dist[4]);
    out << "[" << Quoted(camera.name) << "]\n"
        << "name = " << Quoted(camera.name) << "\n"
        << "size = " << List({double(camera.width), double(camera.height)}) << "\n"
        << "matrix = [ " << List({camera.K(0, 0), camera.K(0, 1), camera.K(0, 2)}) << ", "
        << List({camera.K(1, 0), camera.K(1, 1), camera.K(1, 2)}) << ", "
        << List({camera.K(2, 0), camera.K(2, 1), camera.K(2, 2)}) << "]\n"
        << "distortions = " << List(distortions) << "\n"
        << "rotation = " << List({rvec.x(), rvec.y(), rvec.z()}) << "\n"
        << "translation = " << List({camera.translation.x(), camera.translation.y(), camera.translation.z()}) << "\n"
        << "fisheye = false\n\n";
  }
  out << "[metadata]\nadjusted = false\nerror = 0.0\n";
  WriteTextFile(path, out.str());
}

}  // namespace confluent
