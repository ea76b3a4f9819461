#pragma once
// Plausibility checks of a calibrated rig: geometry, units, handedness, visual-hull consistency.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"

namespace confluent {

// Thresholds for CheckRig.
struct RigCheckOptions {
  double max_plausible_extent_m = 30.0;   // a rig wider than this suggests mm/cm units
  double min_plausible_extent_m = 0.2;    // a rig smaller than this suggests wrong scaling
  double max_axis_miss_angle_deg = 25.0;  // optical axis may point this far from the rig centre
  void Check() const;
};

// Per-camera findings.
struct CameraCheck {
  std::string name;
  double distance_to_center_m = 0;  // from the point the optical axes converge to
  double axis_miss_angle_deg = 0;   // angle between the optical axis and the direction to it
  bool looks_at_volume = false;     // axis_miss_angle_deg <= threshold and centre in front
  bool center_in_image = false;     // the convergence point projects inside the image
  double focal_px = 0;              // mean of fx and fy
  double horizontal_fov_deg = 0;
  double vertical_fov_deg = 0;
};

// The whole report.
struct RigCheckReport {
  Eigen::Vector3d volume_center = Eigen::Vector3d::Zero();  // least-squares convergence point
  double extent_m = 0;                                      // largest camera-centre distance
  std::vector<CameraCheck> cameras;
  Eigen::MatrixXd baseline_m;          // pairwise camera-centre distances
  std::vector<std::string> warnings;   // implausible units, mixed handedness, cameras facing away
  std::string ToString() const;        // human-readable table plus warnings
};

// Checks `rig` geometry. Never throws for implausible values: they become warnings.
RigCheckReport CheckRig(const Rig& rig, const RigCheckOptions& options = {});

// Options for VisualHullConsistency.
struct VisualHullOptions {
  int grid_resolution = 160;     // voxels along the longest side of the carving box
  double box_half_size_m = 0.0;  // half-size of the carving cube; 0 = from the masks' rays
  // A voxel stays in a target's hull when at most this many of its source cameras reject it
  // (0: a strict hull; 1 or more: one camera's hole does not carve the others' hull).
  int tolerated_rejections = 0;
  int threads = 1;  // the carving and the targets' projections split over this many threads (same result)
  void Check() const;
};

// The hull seen from below (and from above): the centre of the lowest (highest) voxel of each
// vertical (z) column of voxels that holds any, and the voxel size.
struct HullUnderside {
  double voxel_m = 0;
  std::vector<Eigen::Vector3d> lowest;
  std::vector<Eigen::Vector3d> highest;  // of the same columns
  // The volume of the hull that every source camera carves (a voxel stays when at most
  // tolerated_rejections of them reject it), cubic metres.
  double volume_m3 = 0;
};

// Visual-hull consistency: for each camera in `targets` (all cameras when empty), carve a
// hull from the masks of the other cameras (all non-target cameras when `targets` is given;
// every other camera otherwise), project it into the target and compare with its mask.
// `masks[i]` is a 1-channel 8-bit mask (0/255) of rig camera i. Returns IoU per target camera
// (same order as `targets`, or rig order). `hull_masks`, if given, receives the projected hulls;
// `underside` the underside of the union of the targets' hulls.
std::vector<double> VisualHullConsistency(const Rig& rig, const std::vector<Image>& masks,
                                          const std::vector<int>& targets, const VisualHullOptions& options = {},
                                          std::vector<Image>* hull_masks = nullptr,
                                          HullUnderside* underside = nullptr);

// An overlay of the world axes (X red, Y green, Z blue, 1 m) and a 1 m ground grid on z = 0
// projected into `camera`, drawn onto `image` (8-bit RGB; distortion respected).
Image DrawWorldOverlay(const Camera& camera, const Image& image, double grid_half_size_m = 5.0);

// Intersection over union of two 0/255 masks of equal size (1 when both are empty).
double MaskIoU(const Image& a, const Image& b);

}  // namespace confluent
