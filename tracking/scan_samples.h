#pragma once
// Samples of a scan's surface and nearest-point queries on them, for the template-to-scan
// registration (scan_registration.cc). Internal to tracking/.

#include <Eigen/Core>
#include <vector>

#include "core/mesh.h"

namespace confluent {
namespace tracking_internal {

// Nearest-neighbour queries on scan samples: a static k-d tree.
class KdTree {
 public:
  explicit KdTree(const std::vector<Eigen::Vector3d>* points);

  // Index of the nearest point, or -1 when empty; `distance2` its squared distance.
  int Nearest(const Eigen::Vector3d& q, double* distance2) const;

 private:
  struct Node {
    int begin, end, axis = -1, left = -1, right = -1;
    double split = 0;
  };

  int Build(int begin, int end);
  void Search(int id, const Eigen::Vector3d& q, int* best, double* best_d2) const;

  const std::vector<Eigen::Vector3d>* points_;
  std::vector<int> index_;
  std::vector<Node> nodes_;
  int root_ = -1;
};

// Area-uniform samples of the scan surface with their face normals.
struct ScanSamples {
  std::vector<Eigen::Vector3d> points, normals;
  double spacing = 0.0;  // typical distance between neighbouring samples
};

// `count` area-uniform (stratified, fixed seed) samples of `scan` with their face normals,
// negated when `flip_normals` (a scan whose faces point inwards). Degenerate faces get none.
ScanSamples SampleScan(const Mesh& scan, int count, bool flip_normals);

}  // namespace tracking_internal
}  // namespace confluent
