#include "tracking/hull_placement.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "calib/rig_check.h"
#include "silhouette/overlap.h"

namespace confluent {

using Eigen::Vector3d;

HullPlacement EstimatePlacementFromHull(const Rig& rig, const std::vector<Image>& masks, const std::vector<bool>& use_camera,
                                        double voxel_m, double half_size_m) {
  HullPlacement out;
  out.voxel_m = voxel_m;
  const RigCheckReport report = CheckRig(rig);
  const Vector3d center = report.volume_center;
  std::vector<int> cams;
  std::vector<Image> small;
  const int downscale = 4;
  for (int c = 0; c < rig.size(); ++c) {
    if ((!use_camera.empty() && !use_camera[c]) || c >= static_cast<int>(masks.size()) || masks[c].empty()) continue;
    cams.push_back(c);
    small.push_back(DownscaleMask(masks[c], downscale));
  }
  if (cams.size() < 2) return out;
  const int n = std::max(2, static_cast<int>(std::ceil(2.0 * half_size_m / voxel_m)));
  const Vector3d origin = center - Vector3d::Constant(half_size_m) + Vector3d::Constant(0.5 * voxel_m);
  std::vector<Vector3d> occupied;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vector3d p = origin + voxel_m * Vector3d(i, j, k);
        int seen = 0;
        bool carved = false;
        for (std::size_t c = 0; c < cams.size() && !carved; ++c) {
          const Camera& camera = rig.cameras[cams[c]];
          Eigen::Vector2d px;
          if (!camera.ProjectChecked(p, &px)) continue;
          const Image& m = small[c];
          const int x = static_cast<int>(std::floor((px.x() + 0.5) * m.width / camera.width));
          const int y = static_cast<int>(std::floor((px.y() + 0.5) * m.height / camera.height));
          if (x < 0 || y < 0 || x >= m.width || y >= m.height) continue;
          ++seen;
          if (!m.at<std::uint8_t>(x, y)) carved = true;
        }
        if (!carved && seen >= 2) occupied.push_back(p);
      }
  out.num_voxels = static_cast<int>(occupied.size());
  if (occupied.empty()) return out;
  Vector3d mean = Vector3d::Zero();
  double zmin = 1e9, zmax = -1e9;
  for (const Vector3d& p : occupied) {
    mean += p;
    zmin = std::min(zmin, p.z());
    zmax = std::max(zmax, p.z());
  }
  mean /= occupied.size();
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const Vector3d& p : occupied) {
    const Eigen::Vector2d d = (p - mean).head<2>();
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  const Eigen::Vector2d major = eig.eigenvectors().col(1);
  out.ok = true;
  out.centroid = mean;
  out.floor_z = zmin - 0.5 * voxel_m;
  out.height_m = zmax - zmin + voxel_m;
  out.yaw_rad = std::atan2(major.y(), major.x());
  return out;
}

}  // namespace confluent
