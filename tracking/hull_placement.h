#pragma once
// Where a person stands, measured on the visual hull of the masks (the tracker's first placement).

#include <Eigen/Core>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"

namespace confluent {

// Global placement of a person from the visual hull of the masks.
struct HullPlacement {
  bool ok = false;                 // false when no voxel survived carving
  int num_voxels = 0;
  double voxel_m = 0.0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // world, m
  double floor_z = 0.0;            // lowest voxel (bottom face), m
  double height_m = 0.0;           // highest minus lowest voxel face, m
  double yaw_rad = 0.0;            // rotation about +z taking the template's lateral (x) axis to the hull's major horizontal axis
};

// Carves a voxel hull (cube of `half_size_m` around the rig's convergence point, cells of
// `voxel_m`) from the masks of the cameras with use_camera[i] (all when empty) and measures it.
HullPlacement EstimatePlacementFromHull(const Rig& rig, const std::vector<Image>& masks, const std::vector<bool>& use_camera,
                                        double voxel_m = 0.03, double half_size_m = 1.6);

}  // namespace confluent
