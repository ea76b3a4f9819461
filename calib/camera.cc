// Camera (OpenCV pinhole + k1 k2 p1 p2 k3) and Rig.

#include "calib/camera.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace confluent {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// Distorted normalized coordinates and their 2x2 Jacobian with respect to `p`.
Eigen::Vector2d DistortWithJacobian(const Vector5d& dist, const Eigen::Vector2d& p, Eigen::Matrix2d* jacobian) {
  const double k1 = dist[0], k2 = dist[1], p1 = dist[2], p2 = dist[3], k3 = dist[4];
  const double x = p.x(), y = p.y();
  const double xx = x * x, yy = y * y, xy = x * y;
  const double r2 = xx + yy;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const Eigen::Vector2d distorted(x * radial + 2.0 * p1 * xy + p2 * (r2 + 2.0 * xx),
                                  y * radial + p1 * (r2 + 2.0 * yy) + 2.0 * p2 * xy);
  if (jacobian != nullptr) {
    // d radial / d r2
    const double dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);
    // d r2 / dx = 2x, d r2 / dy = 2y
    (*jacobian)(0, 0) = radial + x * dradial * 2.0 * x + 2.0 * p1 * y + p2 * 6.0 * x;
    (*jacobian)(0, 1) = x * dradial * 2.0 * y + 2.0 * p1 * x + p2 * 2.0 * y;
    (*jacobian)(1, 0) = y * dradial * 2.0 * x + p1 * 2.0 * x + 2.0 * p2 * y;
    (*jacobian)(1, 1) = radial + y * dradial * 2.0 * y + p1 * 6.0 * y + 2.0 * p2 * x;
  }
  return distorted;
}

// Normalized (z = 1) coordinates -> pixel through K (skew allowed).
Eigen::Vector2d ApplyK(const Eigen::Matrix3d& K, const Eigen::Vector2d& normalized) {
  return Eigen::Vector2d(K(0, 0) * normalized.x() + K(0, 1) * normalized.y() + K(0, 2),
                         K(1, 1) * normalized.y() + K(1, 2));
}

// Pixel -> normalized (z = 1) coordinates through K^-1 (upper triangular K).
Eigen::Vector2d InverseK(const Eigen::Matrix3d& K, const Eigen::Vector2d& pixel) {
  const double y = (pixel.y() - K(1, 2)) / K(1, 1);
  const double x = (pixel.x() - K(0, 2) - K(0, 1) * y) / K(0, 0);
  return Eigen::Vector2d(x, y);
}

template <typename Derived>
bool AllFinite(const Eigen::MatrixBase<Derived>& m) {
  return m.allFinite();
}

}  // namespace

Camera ResizedCamera(Camera camera, int width_px, int height_px) {
  const double sx = static_cast<double>(width_px) / camera.width, sy = static_cast<double>(height_px) / camera.height;
  camera.K(0, 0) *= sx;
  camera.K(0, 1) *= sx;
  camera.K(0, 2) = (camera.K(0, 2) + 0.5) * sx - 0.5;
  camera.K(1, 1) *= sy;
  camera.K(1, 2) = (camera.K(1, 2) + 0.5) * sy - 0.5;
  camera.width = width_px;
  camera.height = height_px;
  return camera;
}

Camera LookAtCamera(const std::string& name, const Eigen::Vector3d& center_in_world,
                    const Eigen::Vector3d& target_in_world, int width_px, int height_px, double focal_px) {
  const Eigen::Vector3d z = (target_in_world - center_in_world).normalized();
  Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ());
  if (x.norm() < 1e-9) x = Eigen::Vector3d::UnitX();  // looking straight up or down
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Camera camera;
  camera.name = name;
  camera.width = width_px;
  camera.height = height_px;
  camera.K << focal_px, 0, (width_px - 1) / 2.0, 0, focal_px, (height_px - 1) / 2.0, 0, 0, 1;
  camera.rotation.row(0) = x.transpose();
  camera.rotation.row(1) = y.transpose();
  camera.rotation.row(2) = z.transpose();
  camera.translation = -camera.rotation * center_in_world;
  return camera;
}

Eigen::Isometry3d Camera::cam_from_world() const {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.linear() = rotation;
  transform.translation() = translation;
  return transform;
}

Eigen::Vector2d Camera::Project(const Eigen::Vector3d& point_in_world) const {
  const Eigen::Vector3d point_in_camera = PointInCamera(point_in_world);
  return ApplyK(K, Distort(point_in_camera.head<2>() / point_in_camera.z()));
}

bool Camera::ProjectChecked(const Eigen::Vector3d& point_in_world, Eigen::Vector2d* pixel) const {
  const Eigen::Vector3d point_in_camera = PointInCamera(point_in_world);
  if (!(point_in_camera.z() > 0.0)) return false;
  *pixel = ApplyK(K, Distort(point_in_camera.head<2>() / point_in_camera.z()));
  return true;
}

Eigen::Vector2d Camera::Distort(const Eigen::Vector2d& normalized) const {
  return DistortWithJacobian(dist, normalized, nullptr);
}

Eigen::Vector2d Camera::Undistort(const Eigen::Vector2d& distorted_normalized) const {
  if (!has_distortion()) return distorted_normalized;
  // Newton iteration on F(p) = Distort(p) - target, started at the target, with step halving
  // when a step does not reduce the residual (strong distortion far from the centre).
  Eigen::Vector2d p = distorted_normalized;
  Eigen::Matrix2d jacobian;
  Eigen::Vector2d residual = DistortWithJacobian(dist, p, &jacobian) - distorted_normalized;
  double residual_norm = residual.norm();
  const double scale = std::max(1.0, distorted_normalized.norm());
  for (int iteration = 0; iteration < 100 && residual_norm > 1e-15 * scale; ++iteration) {
    const double det = jacobian.determinant();
    if (!std::isfinite(det) || std::abs(det) < 1e-300) break;
    const Eigen::Vector2d step = jacobian.inverse() * residual;
    double factor = 1.0;
    bool improved = false;
    for (int halving = 0; halving < 30; ++halving) {
      const Eigen::Vector2d candidate = p - factor * step;
      Eigen::Matrix2d candidate_jacobian;
      const Eigen::Vector2d candidate_residual =
          DistortWithJacobian(dist, candidate, &candidate_jacobian) - distorted_normalized;
      const double candidate_norm = candidate_residual.norm();
      if (candidate_norm < residual_norm) {
        p = candidate;
        residual = candidate_residual;
        residual_norm = candidate_norm;
        jacobian = candidate_jacobian;
        improved = true;
        break;
      }
      factor *= 0.5;
    }
    if (!improved) break;
    if ((factor * step).norm() < 1e-14 * scale) break;
  }
  return p;
}

Eigen::Vector2d Camera::UndistortPixel(const Eigen::Vector2d& pixel) const {
  return ApplyK(K, Undistort(InverseK(K, pixel)));
}

Eigen::Vector2d Camera::DistortPixel(const Eigen::Vector2d& ideal_pixel) const {
  return ApplyK(K, Distort(InverseK(K, ideal_pixel)));
}

Eigen::Vector3d Camera::RayInWorld(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d normalized = Undistort(InverseK(K, pixel));
  const Eigen::Vector3d ray_in_camera = Eigen::Vector3d(normalized.x(), normalized.y(), 1.0).normalized();
  return rotation.transpose() * ray_in_camera;
}

Eigen::Vector3d Camera::Unproject(const Eigen::Vector2d& pixel, double depth_m) const {
  const Eigen::Vector2d normalized = Undistort(InverseK(K, pixel));
  const Eigen::Vector3d point_in_camera(normalized.x() * depth_m, normalized.y() * depth_m, depth_m);
  return rotation.transpose() * (point_in_camera - translation);
}

// The image spans [-0.5, width - 0.5] in pixel coordinates (pixel centres at integers).
double Camera::horizontal_fov_deg() const {
  return (std::atan((K(0, 2) + 0.5) / K(0, 0)) + std::atan((width - 0.5 - K(0, 2)) / K(0, 0))) * kRadToDeg;
}

double Camera::vertical_fov_deg() const {
  return (std::atan((K(1, 2) + 0.5) / K(1, 1)) + std::atan((height - 0.5 - K(1, 2)) / K(1, 1))) * kRadToDeg;
}

void Camera::Check(const std::string& source) const {
  auto fail = [&](const std::string& problem) { throw InputError(source, "camera " + name + ": " + problem); };
  if (!AllFinite(K)) fail("K contains NaN or infinite values");
  if (!AllFinite(dist)) fail("distortion contains NaN or infinite values");
  if (!AllFinite(rotation)) fail("rotation contains NaN or infinite values");
  if (!AllFinite(translation)) fail("translation contains NaN or infinite values");
  if (!(K(0, 0) > 0.0) || !(K(1, 1) > 0.0)) {
    std::ostringstream out;
    out << "focal length must be positive (fx " << K(0, 0) << ", fy " << K(1, 1) << ")";
    fail(out.str());
  }
  if (K(1, 0) != 0.0 || K(2, 0) != 0.0 || K(2, 1) != 0.0 || K(2, 2) != 1.0)
    fail("K must be upper triangular with K(2,2) = 1");
  if (width <= 0 || height <= 0) {
    std::ostringstream out;
    out << "image size must be positive (" << width << "x" << height << ")";
    fail(out.str());
  }
  const double orthogonality_error = (rotation * rotation.transpose() - Eigen::Matrix3d::Identity()).norm();
  const double det = rotation.determinant();
  if (orthogonality_error > 1e-6 || std::abs(det - 1.0) > 1e-6) {
    std::ostringstream out;
    out << "rotation is not a proper rotation (|R R^T - I| = " << orthogonality_error << ", det = " << det << ")";
    fail(out.str());
  }
}

Image UndistortImage(const Camera& camera, const Image& image) {
  if (image.empty()) return image;
  cv::Mat map_x(image.height, image.width, CV_32FC1);
  cv::Mat map_y(image.height, image.width, CV_32FC1);
  for (int y = 0; y < image.height; ++y) {
    float* row_x = map_x.ptr<float>(y);
    float* row_y = map_y.ptr<float>(y);
    for (int x = 0; x < image.width; ++x) {
      const Eigen::Vector2d source = camera.DistortPixel(Eigen::Vector2d(x, y));
      row_x[x] = static_cast<float>(source.x());
      row_y[x] = static_cast<float>(source.y());
    }
  }
  const int depth = image.type == PixelType::kUInt8 ? CV_8U : image.type == PixelType::kUInt16 ? CV_16U : CV_32F;
  const int cv_type = CV_MAKETYPE(depth, image.channels);
  const cv::Mat input(image.height, image.width, cv_type, const_cast<std::uint8_t*>(image.data.data()));
  Image result(image.width, image.height, image.channels, image.type);
  cv::Mat output(result.height, result.width, cv_type, result.data.data());
  cv::remap(input, output, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
  return result;
}

int Rig::IndexOf(const std::string& name) const {
  for (int i = 0; i < size(); ++i)
    if (cameras[i].name == name) return i;
  return -1;
}

const Camera& Rig::Get(const std::string& name) const {
  const int index = IndexOf(name);
  if (index < 0) {
    std::string known;
    for (const auto& camera : cameras) known += (known.empty() ? "" : ", ") + camera.name;
    throw UsageError("unknown camera '" + name + "' (known: " + (known.empty() ? "none" : known) + ")");
  }
  return cameras[index];
}

std::vector<std::string> Rig::names() const {
  std::vector<std::string> result;
  result.reserve(cameras.size());
  for (const auto& camera : cameras) result.push_back(camera.name);
  return result;
}

void Rig::Check(const std::string& source) const {
  std::set<std::string> seen;
  for (const auto& camera : cameras) {
    if (camera.name.empty()) throw InputError(source, "a camera has an empty name");
    if (!seen.insert(camera.name).second) throw InputError(source, "camera name '" + camera.name + "' appears twice");
    camera.Check(source);
  }
}

void TransformWorld(Rig* rig, const Eigen::Matrix3d& rotation_new_from_old, double scale) {
  if (!(scale > 0.0) || !std::isfinite(scale)) throw UsageError("TransformWorld: scale must be positive");
  // point_in_camera * scale = R_cam R^T point_in_new_world + scale * t
  const Eigen::Matrix3d old_from_new = rotation_new_from_old.transpose();
  for (auto& camera : rig->cameras) {
    camera.rotation = camera.rotation * old_from_new;
    camera.translation *= scale;
  }
}

}  // namespace confluent
