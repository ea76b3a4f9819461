#pragma once
// Calibrated pinhole camera with OpenCV's k1 k2 p1 p2 k3 distortion, and a rig of them.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/image.h"

namespace confluent {

using Vector5d = Eigen::Matrix<double, 5, 1>;

// OpenCV camera model. Camera frame: x right, y down, z forward. Pixel (0,0) centre at (0,0).
//   point_in_camera = rotation * point_in_world + translation   (cam_from_world, metres)
//   pixel = K * distort(point_in_camera.xy / point_in_camera.z)
struct Camera {
  std::string name;
  int width = 0;   // image size in pixels
  int height = 0;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();  // fx 0 cx; 0 fy cy; 0 0 1 (skew allowed)
  Vector5d dist = Vector5d::Zero();                 // k1 k2 p1 p2 k3
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // cam_from_world rotation
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();   // cam_from_world translation, m

  bool has_distortion() const { return !dist.isZero(0.0); }
  Eigen::Vector3d center_in_world() const { return -rotation.transpose() * translation; }
  // Unit viewing direction (camera +z) in world coordinates.
  Eigen::Vector3d optical_axis_in_world() const { return rotation.row(2).transpose(); }
  Eigen::Isometry3d cam_from_world() const;

  Eigen::Vector3d PointInCamera(const Eigen::Vector3d& point_in_world) const {
    return rotation * point_in_world + translation;
  }
  // Projects a world point to distorted pixel coordinates. Points behind the camera still
  // give a (meaningless) pixel; use ProjectChecked to reject them.
  Eigen::Vector2d Project(const Eigen::Vector3d& point_in_world) const;
  // As Project, but returns false when the point is not in front of the camera (z <= 0).
  bool ProjectChecked(const Eigen::Vector3d& point_in_world, Eigen::Vector2d* pixel) const;

  // Normalized image coordinates (x/z, y/z) -> distorted normalized coordinates.
  Eigen::Vector2d Distort(const Eigen::Vector2d& normalized) const;
  // Inverse of Distort, by Newton iteration; exact to ~1e-12 inside the image.
  Eigen::Vector2d Undistort(const Eigen::Vector2d& distorted_normalized) const;
  // Distorted pixel -> pixel of the ideal (distortion-free) camera with the same K.
  Eigen::Vector2d UndistortPixel(const Eigen::Vector2d& pixel) const;
  // Ideal (distortion-free) pixel -> distorted pixel.
  Eigen::Vector2d DistortPixel(const Eigen::Vector2d& ideal_pixel) const;

  // Distorted pixel -> unit ray direction in world coordinates (from center_in_world()).
  Eigen::Vector3d RayInWorld(const Eigen::Vector2d& pixel) const;
  // Distorted pixel and depth (camera z, metres) -> world point. Inverse of Project.
  Eigen::Vector3d Unproject(const Eigen::Vector2d& pixel, double depth_m) const;

  // Horizontal and vertical field of view in degrees (pinhole, ignoring distortion).
  double horizontal_fov_deg() const;
  double vertical_fov_deg() const;

  // Throws InputError(`source`, "camera <name>: <problem>") when a value is NaN or infinite,
  // the focal length is not positive, the size is not positive, or rotation is not a proper
  // rotation (orthonormal, det +1, to 1e-6).
  void Check(const std::string& source = {}) const;
};

// A camera at `center_in_world` looking at `target_in_world`, image x along the horizontal
// (world up = +z maps to image up), principal point at the image centre, no distortion.
Camera LookAtCamera(const std::string& name, const Eigen::Vector3d& center_in_world,
                    const Eigen::Vector3d& target_in_world, int width_px, int height_px, double focal_px);

// The same camera with its image resized to width_px x height_px (K scaled so that pixel
// centres stay at integers; distortion, which acts on normalised coordinates, is unchanged).
Camera ResizedCamera(Camera camera, int width_px, int height_px);

// Undistorts an image so it matches the ideal pinhole camera with the same K (bilinear).
Image UndistortImage(const Camera& camera, const Image& image);

// A set of calibrated cameras with unique names, in a fixed order.
struct Rig {
  std::vector<Camera> cameras;

  int size() const { return static_cast<int>(cameras.size()); }
  // Index of the camera called `name`, or -1.
  int IndexOf(const std::string& name) const;
  // The camera called `name`; throws UsageError listing the known names if there is none.
  const Camera& Get(const std::string& name) const;
  std::vector<std::string> names() const;
  // Camera::Check for every camera, plus unique, non-empty names. Throws InputError(`source`).
  void Check(const std::string& source = {}) const;
};

// Applies a similarity to the world frame: point_in_new_world = scale * R * point_in_world.
// Every camera keeps imaging the same points.
void TransformWorld(Rig* rig, const Eigen::Matrix3d& rotation_new_from_old, double scale);

}  // namespace confluent
