#include "calib/rig_check.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/cv_interop.h"
#include "core/error.h"
#include "core/parallel.h"

namespace confluent {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// The point closest (least squares) to every camera's optical axis.
Eigen::Vector3d ConvergencePoint(const Rig& rig) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero(), mean = Eigen::Vector3d::Zero();
  for (const Camera& camera : rig.cameras) {
    const Eigen::Vector3d d = camera.optical_axis_in_world().normalized();
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - d * d.transpose();
    A += P;
    b += P * camera.center_in_world();
    mean += camera.center_in_world();
  }
  mean /= std::max(1, rig.size());
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (rig.size() < 2 || svd.singularValues()(2) < 1e-6 * std::max(1.0, svd.singularValues()(0))) return mean;
  return svd.solve(b);
}

}  // namespace

void RigCheckOptions::Check() const {
  const std::string owner = "RigCheckOptions.";
  RequireOption(min_plausible_extent_m > 0, owner + "min_plausible_extent_m", min_plausible_extent_m, "> 0");
  RequireOptions(max_plausible_extent_m > min_plausible_extent_m, owner + "min_plausible_extent_m",
                 min_plausible_extent_m, owner + "max_plausible_extent_m", max_plausible_extent_m,
                 "min_plausible_extent_m < max_plausible_extent_m");
  RequireOption(max_axis_miss_angle_deg > 0 && max_axis_miss_angle_deg < 180, owner + "max_axis_miss_angle_deg",
                max_axis_miss_angle_deg, "in (0, 180)");
}

RigCheckReport CheckRig(const Rig& rig, const RigCheckOptions& options) {
  options.Check();
  RigCheckReport report;
  const int n = rig.size();
  report.volume_center = ConvergencePoint(rig);
  report.baseline_m = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      report.baseline_m(i, j) = (rig.cameras[i].center_in_world() - rig.cameras[j].center_in_world()).norm();
  report.extent_m = n > 0 ? report.baseline_m.maxCoeff() : 0.0;

  int positive_handed = 0, negative_handed = 0;
  Eigen::Vector3d mean_up = Eigen::Vector3d::Zero();
  for (const Camera& camera : rig.cameras) {
    CameraCheck check;
    check.name = camera.name;
    const Eigen::Vector3d to_center = report.volume_center - camera.center_in_world();
    check.distance_to_center_m = to_center.norm();
    const double cosine = to_center.normalized().dot(camera.optical_axis_in_world().normalized());
    check.axis_miss_angle_deg = std::acos(std::clamp(cosine, -1.0, 1.0)) * kRadToDeg;
    Eigen::Vector2d pixel;
    check.center_in_image = camera.ProjectChecked(report.volume_center, &pixel) && pixel.x() >= -0.5 &&
                            pixel.y() >= -0.5 && pixel.x() < camera.width - 0.5 && pixel.y() < camera.height - 0.5;
    check.looks_at_volume = cosine > 0 && check.axis_miss_angle_deg <= options.max_axis_miss_angle_deg;
    check.focal_px = 0.5 * (camera.K(0, 0) + camera.K(1, 1));
    check.horizontal_fov_deg = camera.horizontal_fov_deg();
    check.vertical_fov_deg = camera.vertical_fov_deg();
    (camera.rotation.determinant() > 0 ? positive_handed : negative_handed)++;
    mean_up += -camera.rotation.row(1).transpose();  // camera -y is "up" in the image
    if (!check.looks_at_volume)
      report.warnings.push_back("camera " + camera.name + " faces away from the capture volume (axis misses it by " +
                                std::to_string(static_cast<int>(check.axis_miss_angle_deg)) + " deg)");
    report.cameras.push_back(check);
  }
  std::ostringstream extent;
  extent << std::fixed << std::setprecision(2) << report.extent_m;
  if (n >= 2 && report.extent_m > options.max_plausible_extent_m)
    report.warnings.push_back("rig is " + extent.str() + " m across: implausible for a studio; are the units mm or cm? "
                              "(convert with --units)");
  if (n >= 2 && report.extent_m < options.min_plausible_extent_m)
    report.warnings.push_back("rig is only " + extent.str() + " m across: are the units km or scaled?");
  if (positive_handed > 0 && negative_handed > 0)
    report.warnings.push_back("mixed handedness: " + std::to_string(negative_handed) +
                              " camera(s) have a reflection (det R = -1)");
  if (n > 0 && mean_up.norm() > 1e-9 && mean_up.normalized().z() < 0.5)
    report.warnings.push_back("the cameras' up direction is not world +Z (mean up = (" +
                              std::to_string(mean_up.normalized().x()).substr(0, 5) + ", " +
                              std::to_string(mean_up.normalized().y()).substr(0, 5) + ", " +
                              std::to_string(mean_up.normalized().z()).substr(0, 5) +
                              ")): convert with --up so that the world is Z up");
  return report;
}

std::string RigCheckReport::ToString() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3);
  out << "capture volume centre (m): " << volume_center.transpose() << "   rig extent: " << extent_m << " m\n";
  out << "camera        dist_m  miss_deg  looks  focal_px  hfov_deg  vfov_deg  nearest_baseline_m\n";
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const CameraCheck& c = cameras[i];
    double nearest = 0;
    for (std::size_t j = 0; j < cameras.size(); ++j)
      if (j != i && (nearest == 0 || baseline_m(i, j) < nearest)) nearest = baseline_m(i, j);
    char line[256];
    std::snprintf(line, sizeof line, "%-12s %7.3f %9.2f  %-5s %9.1f %9.2f %9.2f  %9.3f\n", c.name.c_str(),
                  c.distance_to_center_m, c.axis_miss_angle_deg, c.looks_at_volume ? "yes" : "NO", c.focal_px,
                  c.horizontal_fov_deg, c.vertical_fov_deg, nearest);
    out << line;
  }
  for (const auto& warning : warnings) out << "warning: " << warning << "\n";
  return out.str();
}

void VisualHullOptions::Check() const {
  RequireOption(grid_resolution >= 8 && grid_resolution <= 1024, "VisualHullOptions.grid_resolution", grid_resolution,
                "in [8, 1024]");
  RequireOption(box_half_size_m >= 0, "VisualHullOptions.box_half_size_m", box_half_size_m, ">= 0");
  RequireOption(tolerated_rejections >= 0 && tolerated_rejections <= 8, "VisualHullOptions.tolerated_rejections",
                tolerated_rejections, "in [0, 8]");
  RequireOption(threads >= 1, "VisualHullOptions.threads", threads, ">= 1");
}

namespace {

// Voxel grid over an axis-aligned box.
struct Grid {
  Eigen::Vector3d origin;  // centre of voxel (0,0,0)
  double voxel_m = 0;
  Eigen::Vector3i size;
  Eigen::Vector3d Center(int x, int y, int z) const { return origin + voxel_m * Eigen::Vector3d(x, y, z); }
  long Index(int x, int y, int z) const { return (static_cast<long>(z) * size.y() + y) * size.x() + x; }
  long count() const { return static_cast<long>(size.x()) * size.y() * size.z(); }
};

Grid MakeGrid(const Eigen::Vector3d& lower, const Eigen::Vector3d& upper, int resolution) {
  Grid grid;
  const Eigen::Vector3d extent = (upper - lower).cwiseMax(1e-6);
  grid.voxel_m = extent.maxCoeff() / resolution;
  for (int a = 0; a < 3; ++a) grid.size[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / grid.voxel_m)));
  grid.origin = lower + Eigen::Vector3d::Constant(0.5 * grid.voxel_m);
  return grid;
}

// True when `mask` rejects the point: it projects onto background, or outside the camera's
// view (the hull lies inside every source camera's field of view).
bool Rejects(const Camera& camera, const Image& mask, const Eigen::Vector3d& point) {
  Eigen::Vector2d pixel;
  if (!camera.ProjectChecked(point, &pixel)) return true;
  const int x = static_cast<int>(std::lround(pixel.x())), y = static_cast<int>(std::lround(pixel.y()));
  if (x < 0 || y < 0 || x >= mask.width || y >= mask.height) return true;
  return mask.data[static_cast<std::size_t>(y) * mask.width + x] == 0;
}

}  // namespace

std::vector<double> VisualHullConsistency(const Rig& rig, const std::vector<Image>& masks,
                                          const std::vector<int>& targets, const VisualHullOptions& options,
                                          std::vector<Image>* hull_masks, HullUnderside* underside) {
  options.Check();
  if (underside != nullptr) *underside = HullUnderside();
  const int n = rig.size();
  if (static_cast<int>(masks.size()) != n) throw UsageError("VisualHullConsistency: one mask per camera is needed");
  for (int i = 0; i < n; ++i)
    if (masks[i].width != rig.cameras[i].width || masks[i].height != rig.cameras[i].height || masks[i].channels != 1)
      throw InputError(rig.cameras[i].name, "mask size does not match the calibration");
  const bool leave_one_out = targets.empty();
  std::vector<int> target_list = targets;
  if (leave_one_out)
    for (int i = 0; i < n; ++i) target_list.push_back(i);
  std::vector<bool> is_source(n, true);
  if (!leave_one_out)
    for (int t : targets) is_source.at(t) = false;

  // Pass 1: a coarse carve with every source camera bounds the hull.
  const RigCheckReport geometry = CheckRig(rig);
  double half = options.box_half_size_m;
  if (half <= 0) {
    std::vector<double> distances;
    for (const auto& c : geometry.cameras) distances.push_back(c.distance_to_center_m);
    std::nth_element(distances.begin(), distances.begin() + distances.size() / 2, distances.end());
    half = 0.75 * distances[distances.size() / 2];
  }
  const Eigen::Vector3d box_lower = geometry.volume_center - Eigen::Vector3d::Constant(half);
  const Eigen::Vector3d box_upper = geometry.volume_center + Eigen::Vector3d::Constant(half);
  Grid coarse = MakeGrid(box_lower, box_upper, 48);
  const int tolerated = options.tolerated_rejections;
  const int allowed = tolerated + (leave_one_out ? 1 : 0);  // rejections a voxel of some hull may have
  // Bounds per slice of z, then over the slices (min and max: the same in any order).
  std::vector<Eigen::Vector3d> slice_lower(coarse.size.z(), Eigen::Vector3d::Constant(1e30));
  std::vector<Eigen::Vector3d> slice_upper(coarse.size.z(), Eigen::Vector3d::Constant(-1e30));
  ParallelFor(coarse.size.z(), options.threads, [&](int z) {
    for (int y = 0; y < coarse.size.y(); ++y)
      for (int x = 0; x < coarse.size.x(); ++x) {
        const Eigen::Vector3d p = coarse.Center(x, y, z);
        int rejections = 0;
        for (int c = 0; c < n && rejections <= allowed; ++c)
          if (is_source[c] && Rejects(rig.cameras[c], masks[c], p)) ++rejections;
        if (rejections <= allowed) {
          slice_lower[z] = slice_lower[z].cwiseMin(p);
          slice_upper[z] = slice_upper[z].cwiseMax(p);
        }
      }
  });
  Eigen::Vector3d lower = Eigen::Vector3d::Constant(1e30), upper = Eigen::Vector3d::Constant(-1e30);
  for (int z = 0; z < coarse.size.z(); ++z) {
    lower = lower.cwiseMin(slice_lower[z]);
    upper = upper.cwiseMax(slice_upper[z]);
  }
  std::vector<double> ious;
  if (lower.x() > upper.x()) {  // nothing survives: every hull is empty
    for (int t : target_list) {
      Image empty(rig.cameras[t].width, rig.cameras[t].height, 1);
      ious.push_back(MaskIoU(empty, masks[t]));
      if (hull_masks) hull_masks->push_back(empty);
    }
    return ious;
  }
  // Thin limbs can fall between coarse voxel centres: pad the bounds generously.
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(3 * coarse.voxel_m);
  Grid grid = MakeGrid(lower - margin, upper + margin, options.grid_resolution);

  // Pass 2: per voxel, how many source cameras reject it (counted up to allowed + 1).
  std::vector<std::uint8_t> rejections(grid.count(), 0);
  ParallelFor(grid.size.z(), options.threads, [&](int z) {
    for (int y = 0; y < grid.size.y(); ++y)
      for (int x = 0; x < grid.size.x(); ++x) {
        const long v = grid.Index(x, y, z);
        const Eigen::Vector3d p = grid.Center(x, y, z);
        for (int c = 0; c < n && rejections[v] <= allowed; ++c)
          if (is_source[c] && Rejects(rig.cameras[c], masks[c], p)) ++rejections[v];
      }
  });

  if (underside != nullptr) {
    underside->voxel_m = grid.voxel_m;
    const long kept = std::count_if(rejections.begin(), rejections.end(),
                                    [tolerated](std::uint8_t count) { return count <= tolerated; });
    underside->volume_m3 = static_cast<double>(kept) * grid.voxel_m * grid.voxel_m * grid.voxel_m;
    for (int y = 0; y < grid.size.y(); ++y)
      for (int x = 0; x < grid.size.x(); ++x)
        for (int z = 0; z < grid.size.z(); ++z)
          if (rejections[grid.Index(x, y, z)] <= allowed) {
            underside->lowest.push_back(grid.Center(x, y, z));
            int top = grid.size.z() - 1;
            while (rejections[grid.Index(x, y, top)] > allowed) --top;
            underside->highest.push_back(grid.Center(x, y, top));
            break;
          }
  }
  ious.assign(target_list.size(), 0.0);
  std::vector<Image> hulls(target_list.size());
  ParallelFor(static_cast<int>(target_list.size()), options.threads, [&](int target_index) {
    const int t = target_list[target_index];
    const Camera& camera = rig.cameras[t];
    auto inside = [&](int x, int y, int z) {
      if (x < 0 || y < 0 || z < 0 || x >= grid.size.x() || y >= grid.size.y() || z >= grid.size.z()) return false;
      const long v = grid.Index(x, y, z);
      if (rejections[v] <= tolerated) return true;
      // One rejection more is allowed when it is the target's own.
      return leave_one_out && rejections[v] == tolerated + 1 && Rejects(camera, masks[t], grid.Center(x, y, z));
    };
    Image hull(camera.width, camera.height, 1);
    cv::Mat canvas = AsCvMat(hull);
    const double focal = 0.5 * (camera.K(0, 0) + camera.K(1, 1));
    for (int z = 0; z < grid.size.z(); ++z)
      for (int y = 0; y < grid.size.y(); ++y)
        for (int x = 0; x < grid.size.x(); ++x) {
          if (!inside(x, y, z)) continue;
          if (inside(x - 1, y, z) && inside(x + 1, y, z) && inside(x, y - 1, z) && inside(x, y + 1, z) &&
              inside(x, y, z - 1) && inside(x, y, z + 1))
            continue;  // interior voxels project inside the surface voxels' footprint
          const Eigen::Vector3d p = grid.Center(x, y, z);
          Eigen::Vector2d pixel;
          if (!camera.ProjectChecked(p, &pixel)) continue;
          const double radius = 0.6 * focal * grid.voxel_m / camera.PointInCamera(p).z();
          cv::circle(canvas, cv::Point(static_cast<int>(std::lround(pixel.x())), static_cast<int>(std::lround(pixel.y()))),
                     std::max(0, static_cast<int>(std::ceil(radius - 0.5))),
                     cv::Scalar(255), cv::FILLED);
        }
    ious[target_index] = MaskIoU(hull, masks[t]);
    hulls[target_index] = std::move(hull);
  });
  if (hull_masks)
    for (Image& hull : hulls) hull_masks->push_back(std::move(hull));
  return ious;
}

Image DrawWorldOverlay(const Camera& camera, const Image& image, double grid_half_size_m) {
  Image canvas_image = image;
  cv::Mat canvas = AsCvMat(canvas_image);
  // The distortion polynomial is only valid inside the field of view: points whose ideal
  // projection lies well outside the image are not drawn (they would curl back into it).
  double max_radius = 0;
  for (const Eigen::Vector2d& corner : {Eigen::Vector2d(0, 0), Eigen::Vector2d(camera.width, 0),
                                       Eigen::Vector2d(0, camera.height), Eigen::Vector2d(camera.width, camera.height)})
    max_radius = std::max(max_radius, camera.Undistort((camera.K.inverse() * corner.homogeneous()).head<2>()).norm());
  auto project = [&](const Eigen::Vector3d& point, Eigen::Vector2d* pixel) {
    const Eigen::Vector3d in_camera = camera.PointInCamera(point);
    if (!(in_camera.z() > 0) || (in_camera.head<2>() / in_camera.z()).norm() > 1.15 * max_radius) return false;
    *pixel = camera.Project(point);
    return true;
  };
  // Draws a world segment as short projected pieces, so distortion bends it correctly.
  auto draw_segment = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const cv::Scalar& color, int thickness) {
    const int pieces = std::max(1, static_cast<int>((b - a).norm() / 0.05));
    Eigen::Vector2d previous;
    bool previous_ok = false;
    for (int i = 0; i <= pieces; ++i) {
      Eigen::Vector2d pixel;
      const bool ok = project(a + (b - a) * (static_cast<double>(i) / pieces), &pixel);
      if (ok && previous_ok)
        cv::line(canvas, cv::Point2d(previous.x(), previous.y()), cv::Point2d(pixel.x(), pixel.y()), color, thickness,
                 cv::LINE_AA);
      previous = pixel;
      previous_ok = ok;
    }
  };
  const int lines = static_cast<int>(std::floor(grid_half_size_m));
  for (int i = -lines; i <= lines; ++i) {
    draw_segment({static_cast<double>(i), -grid_half_size_m, 0}, {static_cast<double>(i), grid_half_size_m, 0},
                 cv::Scalar(255, 255, 255), 1);
    draw_segment({-grid_half_size_m, static_cast<double>(i), 0}, {grid_half_size_m, static_cast<double>(i), 0},
                 cv::Scalar(255, 255, 255), 1);
  }
  const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  draw_segment(origin, Eigen::Vector3d::UnitX(), cv::Scalar(255, 0, 0), 3);  // RGB order
  draw_segment(origin, Eigen::Vector3d::UnitY(), cv::Scalar(0, 255, 0), 3);
  draw_segment(origin, Eigen::Vector3d::UnitZ(), cv::Scalar(0, 0, 255), 3);
  return canvas_image;
}

double MaskIoU(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) throw UsageError("MaskIoU: masks differ in size");
  long intersection = 0, union_count = 0;
  const std::size_t pixels = static_cast<std::size_t>(a.width) * a.height;
  if (a.channels == 1 && b.channels == 1) {  // the common case, in loops the compiler vectorises
    const std::uint8_t* pa = a.data.data();
    const std::uint8_t* pb = b.data.data();
    // 32-bit counts per block of pixels, which vectorise four times wider than 64-bit ones.
    constexpr std::size_t kBlock = std::size_t{1} << 24;
    for (std::size_t begin = 0; begin < pixels; begin += kBlock) {
      const std::size_t end = std::min(pixels, begin + kBlock);
      std::uint32_t block_intersection = 0, block_union = 0;
      for (std::size_t i = begin; i < end; ++i) {
        block_intersection += static_cast<std::uint8_t>(pa[i] & pb[i]) >> 7;
        block_union += static_cast<std::uint8_t>(pa[i] | pb[i]) >> 7;
      }
      intersection += block_intersection;
      union_count += block_union;
    }
    return union_count == 0 ? 1.0 : static_cast<double>(intersection) / union_count;
  }
  for (std::size_t i = 0; i < pixels; ++i) {
    const bool in_a = a.data[i * a.channels] >= 128, in_b = b.data[i * b.channels] >= 128;
    intersection += in_a && in_b;
    union_count += in_a || in_b;
  }
  return union_count == 0 ? 1.0 : static_cast<double>(intersection) / union_count;
}

}  // namespace confluent
