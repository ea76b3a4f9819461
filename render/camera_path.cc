#include "render/camera_path.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"

namespace confluent {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;

// K of `camera` rescaled to a width x height image (pixel centres at integers).
Eigen::Matrix3d RescaledK(const Camera& camera, int width, int height) {
  const double sx = static_cast<double>(width) / camera.width;
  const double sy = static_cast<double>(height) / camera.height;
  Eigen::Matrix3d K = camera.K;
  K(0, 0) *= sx;
  K(0, 1) *= sx;
  K(0, 2) = (camera.K(0, 2) + 0.5) * sx - 0.5;
  K(1, 1) *= sy;
  K(1, 2) = (camera.K(1, 2) + 0.5) * sy - 0.5;
  return K;
}

// Centripetal Catmull-Rom point between p1 (s = 0) and p2 (s = 1) (Barry-Goldman pyramid).
Eigen::Vector3d CatmullRom(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                           const Eigen::Vector3d& p3, double s) {
  auto knot = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::max(std::sqrt((b - a).norm()), 1e-6);
  };
  const double t0 = 0.0;
  const double t1 = t0 + knot(p0, p1);
  const double t2 = t1 + knot(p1, p2);
  const double t3 = t2 + knot(p2, p3);
  const double t = t1 + s * (t2 - t1);
  const Eigen::Vector3d a1 = (t1 - t) / (t1 - t0) * p0 + (t - t0) / (t1 - t0) * p1;
  const Eigen::Vector3d a2 = (t2 - t) / (t2 - t1) * p1 + (t - t1) / (t2 - t1) * p2;
  const Eigen::Vector3d a3 = (t3 - t) / (t3 - t2) * p2 + (t - t2) / (t3 - t2) * p3;
  const Eigen::Vector3d b1 = (t2 - t) / (t2 - t0) * a1 + (t - t0) / (t2 - t0) * a2;
  const Eigen::Vector3d b2 = (t3 - t) / (t3 - t1) * a2 + (t - t1) / (t3 - t1) * a3;
  return (t2 - t) / (t2 - t1) * b1 + (t - t1) / (t2 - t1) * b2;
}

}  // namespace

void OrbitPathOptions::Check() const {
  const std::string owner = "OrbitPathOptions.";
  const Eigen::Vector3d& center = center_in_world;
  RequireOption(center.allFinite(), owner + "center_in_world", {center.x(), center.y(), center.z()}, "finite");
  RequireOption(radius_m >= 0.0 && std::isfinite(radius_m), owner + "radius_m", radius_m, ">= 0 and finite");
  RequireOption(std::isfinite(height_m), owner + "height_m", height_m, "finite");
  RequireOption(std::isfinite(start_angle_deg), owner + "start_angle_deg", start_angle_deg, "finite");
  RequireOption(std::isfinite(sweep_deg), owner + "sweep_deg", sweep_deg, "finite");
  RequireOption(num_frames >= 1, owner + "num_frames", num_frames, ">= 1");
  RequireOption(width_px >= 1, owner + "width_px", width_px, ">= 1");
  RequireOption(height_px >= 1, owner + "height_px", height_px, ">= 1");
  RequireOption(vertical_fov_deg > 0.0 && vertical_fov_deg < 179.0, owner + "vertical_fov_deg", vertical_fov_deg,
                "in (0, 179)");
  RequireOptions(!(radius_m == 0.0 && std::abs(height_m - center.z()) < 1e-9), owner + "radius_m", radius_m,
                 owner + "height_m", height_m,
                 "off the look-at point (radius 0 at center_in_world's height puts the camera on it)");
}

std::vector<Camera> OrbitPath(const OrbitPathOptions& options) {
  options.Check();
  const double focal = 0.5 * options.height_px / std::tan(0.5 * options.vertical_fov_deg * kDegToRad);
  const bool full_turn = std::abs(options.sweep_deg) >= 360.0 - 1e-9;
  const int steps = full_turn ? options.num_frames : std::max(1, options.num_frames - 1);
  std::vector<Camera> path;
  path.reserve(options.num_frames);
  for (int i = 0; i < options.num_frames; ++i) {
    const double angle = (options.start_angle_deg + options.sweep_deg * i / steps) * kDegToRad;
    const Eigen::Vector3d center(options.center_in_world.x() + options.radius_m * std::cos(angle),
                                 options.center_in_world.y() + options.radius_m * std::sin(angle), options.height_m);
    path.push_back(LookAtCamera("orbit_" + std::to_string(i), center, options.center_in_world, options.width_px,
                                options.height_px, focal));
  }
  return path;
}

OrbitPathOptions OrbitAroundCameras(const std::vector<Camera>& cameras, const Eigen::Vector3d& center_in_world) {
  if (cameras.empty()) throw UsageError("an orbit around cameras needs at least one camera");
  OrbitPathOptions options;
  options.center_in_world = center_in_world;
  double radius = 0.0, height = 0.0;
  for (const Camera& camera : cameras) {
    const Eigen::Vector3d c = camera.center_in_world();
    radius += (c - center_in_world).head<2>().norm();
    height += c.z();
  }
  options.radius_m = radius / cameras.size();
  options.height_m = height / cameras.size();
  options.width_px = cameras.front().width;
  options.height_px = cameras.front().height;
  options.vertical_fov_deg = cameras.front().vertical_fov_deg();
  return options;
}

void KeyCameraPathOptions::Check() const {
  RequireOption(num_frames >= 1, "KeyCameraPathOptions.num_frames", num_frames, ">= 1");
  RequireOptions(width_px >= 0 && height_px >= 0 && (width_px == 0) == (height_px == 0),
                 "KeyCameraPathOptions.width_px", width_px, "KeyCameraPathOptions.height_px", height_px,
                 "both 0 (keep) or both positive");
}

std::vector<int> KeyFrameIndices(int num_keys, const KeyCameraPathOptions& options) {
  options.Check();
  if (num_keys < 1) throw UsageError("a camera path needs at least one key camera");
  if (options.closed && num_keys < 2) throw UsageError("a closed camera path needs at least two key cameras");
  if (options.num_frames < num_keys)
    throw UsageError("a camera path through " + std::to_string(num_keys) + " cameras needs at least as many frames, got " +
                     std::to_string(options.num_frames));
  std::vector<int> indices(num_keys, 0);
  for (int j = 0; j < num_keys; ++j) {
    if (options.closed) {
      indices[j] = static_cast<int>(std::lround(static_cast<double>(j) * options.num_frames / num_keys));
    } else if (num_keys > 1) {
      indices[j] = static_cast<int>(std::lround(static_cast<double>(j) * (options.num_frames - 1) / (num_keys - 1)));
    }
  }
  return indices;
}

std::vector<Camera> PathThroughCameras(const std::vector<Camera>& keys, const KeyCameraPathOptions& options) {
  const std::vector<int> key_frames = KeyFrameIndices(static_cast<int>(keys.size()), options);
  for (const Camera& key : keys) key.Check("camera path");
  const int width = options.width_px > 0 ? options.width_px : keys.front().width;
  const int height = options.height_px > 0 ? options.height_px : keys.front().height;
  const int num_keys = static_cast<int>(keys.size());
  std::vector<Eigen::Vector3d> centers;
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Matrix3d> intrinsics;
  for (const Camera& key : keys) {
    centers.push_back(key.center_in_world());
    rotations.emplace_back(key.rotation);
    intrinsics.push_back(RescaledK(key, width, height));
  }
  // Neighbouring key centres, extrapolated at the ends of an open path.
  auto center_at = [&](int j) -> Eigen::Vector3d {
    if (options.closed) return centers[((j % num_keys) + num_keys) % num_keys];
    if (j < 0) return num_keys > 1 ? Eigen::Vector3d(2.0 * centers[0] - centers[1]) : centers[0];
    if (j >= num_keys)
      return num_keys > 1 ? Eigen::Vector3d(2.0 * centers[num_keys - 1] - centers[num_keys - 2]) : centers[num_keys - 1];
    return centers[j];
  };

  std::vector<Camera> path;
  path.reserve(options.num_frames);
  const int num_segments = options.closed ? num_keys : num_keys - 1;
  for (int i = 0; i < options.num_frames; ++i) {
    // Segment j runs from key j (at key_frames[j]) to key j + 1.
    int segment = 0;
    while (segment + 1 < num_segments && i >= key_frames[segment + 1]) ++segment;
    Camera camera;
    camera.name = "path_" + std::to_string(i);
    camera.width = width;
    camera.height = height;
    if (num_segments == 0) {  // one key: a fixed camera
      camera.K = intrinsics[0];
      camera.rotation = keys[0].rotation;
      camera.translation = -camera.rotation * centers[0];
      path.push_back(camera);
      continue;
    }
    const int start_frame = key_frames[segment];
    const int end_frame = segment + 1 < num_keys ? key_frames[segment + 1] : options.num_frames;
    const double s = end_frame > start_frame ? static_cast<double>(i - start_frame) / (end_frame - start_frame) : 0.0;
    const int a = segment, b = (segment + 1) % num_keys;
    Eigen::Vector3d center;
    Eigen::Matrix3d rotation;
    if (s == 0.0 || s == 1.0) {  // exactly on a key
      const int key = s == 0.0 ? a : b;
      center = centers[key];
      rotation = keys[key].rotation;
      camera.K = intrinsics[key];
    } else {
      center = CatmullRom(center_at(segment - 1), center_at(segment), center_at(segment + 1), center_at(segment + 2), s);
      rotation = rotations[a].slerp(s, rotations[b]).normalized().toRotationMatrix();
      camera.K = (1.0 - s) * intrinsics[a] + s * intrinsics[b];
    }
    camera.rotation = rotation;
    camera.translation = -rotation * center;
    path.push_back(camera);
  }
  return path;
}

std::vector<Camera> FixedPath(const Camera& camera, int num_frames) {
  if (num_frames < 1) throw UsageError("a fixed camera path needs at least one frame");
  return std::vector<Camera>(num_frames, camera);
}

std::vector<Camera> SortByAzimuth(const std::vector<Camera>& cameras, const Eigen::Vector3d& center_in_world) {
  std::vector<double> azimuth;
  for (const Camera& camera : cameras) {
    const Eigen::Vector3d d = camera.center_in_world() - center_in_world;
    azimuth.push_back(std::atan2(d.y(), d.x()));
  }
  std::vector<int> order(cameras.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return azimuth[a] < azimuth[b]; });
  std::vector<Camera> sorted;
  for (int index : order) sorted.push_back(cameras[index]);
  return sorted;
}

std::vector<PathFrame> AlongSequence(const std::vector<Camera>& path, const std::vector<int>& frames) {
  if (path.empty() || frames.empty()) throw UsageError("a novel-view sequence needs cameras and frames");
  const int P = static_cast<int>(path.size()), M = static_cast<int>(frames.size());
  std::vector<PathFrame> sequence;
  for (int j = 0; j < M; ++j) {
    const int index = M > 1 ? static_cast<int>(std::lround(static_cast<double>(j) * (P - 1) / (M - 1))) : 0;
    sequence.push_back({path[index], frames[j]});
  }
  return sequence;
}

std::vector<PathFrame> FrozenTime(const std::vector<Camera>& path, int frame) {
  if (path.empty()) throw UsageError("a bullet-time sweep needs at least one camera");
  std::vector<PathFrame> sequence;
  for (const Camera& camera : path) sequence.push_back({camera, frame});
  return sequence;
}

}  // namespace confluent
