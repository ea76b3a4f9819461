#pragma once
// Samples of a scan's surface and nearest-point queries on them, for the template-to-scan
// registration (scan_registration.cc). Internal to tracking/.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <limits>
#include <numeric>
#include <vector>

#include "core/mesh.h"

namespace confluent {
namespace tracking_internal {

// Nearest-neighbour queries on scan samples: a static k-d tree.
class KdTree {
 public:
  explicit KdTree(const std::vector<Eigen::Vector3d>* points) : points_(points) {
    index_.resize(points->size());
    std::iota(index_.begin(), index_.end(), 0);
    if (!index_.empty()) root_ = Build(0, static_cast<int>(index_.size()));
  }

  // Index of the nearest point, or -1 when empty; `distance2` its squared distance.
  int Nearest(const Eigen::Vector3d& q, double* distance2) const {
    int best = -1;
    double best_d2 = std::numeric_limits<double>::infinity();
    if (root_ >= 0) Search(root_, q, &best, &best_d2);
    *distance2 = best_d2;
    return best;
  }

 private:
  struct Node {
    int begin, end, axis = -1, left = -1, right = -1;
    double split = 0;
  };

  int Build(int begin, int end) {
    Node node{begin, end};
    const int id = static_cast<int>(nodes_.size());
    nodes_.push_back(node);
    if (end - begin <= 8) return id;
    Eigen::AlignedBox3d box;
    for (int i = begin; i < end; ++i) box.extend((*points_)[index_[i]]);
    int axis;
    box.sizes().maxCoeff(&axis);
    const int mid = (begin + end) / 2;
    std::nth_element(index_.begin() + begin, index_.begin() + mid, index_.begin() + end,
                     [&](int a, int b) { return (*points_)[a][axis] < (*points_)[b][axis]; });
    nodes_[id].axis = axis;
    nodes_[id].split = (*points_)[index_[mid]][axis];
    const int left = Build(begin, mid);
    const int right = Build(mid, end);
    nodes_[id].left = left;
    nodes_[id].right = right;
    return id;
  }

  void Search(int id, const Eigen::Vector3d& q, int* best, double* best_d2) const {
    const Node& node = nodes_[id];
    if (node.axis < 0) {
      for (int i = node.begin; i < node.end; ++i) {
        const double d2 = ((*points_)[index_[i]] - q).squaredNorm();
        if (d2 < *best_d2) {
          *best_d2 = d2;
          *best = index_[i];
        }
      }
      return;
    }
    const double delta = q[node.axis] - node.split;
    const int first = delta < 0 ? node.left : node.right, second = delta < 0 ? node.right : node.left;
    Search(first, q, best, best_d2);
    if (delta * delta < *best_d2) Search(second, q, best, best_d2);
  }

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

// `count` area-uniform (stratified, fixed seed) samples of `scan` with their face normals, turned
// inwards-out when `flip_normals`. Degenerate faces get none.
ScanSamples SampleScan(const Mesh& scan, int count, bool flip_normals);

}  // namespace tracking_internal
}  // namespace confluent
