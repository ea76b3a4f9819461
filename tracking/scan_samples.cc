#include "tracking/scan_samples.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "core/mesh_ops.h"

namespace confluent {
namespace tracking_internal {

using Eigen::Vector3d;

KdTree::KdTree(const std::vector<Vector3d>* points) : points_(points) {
  index_.resize(points->size());
  std::iota(index_.begin(), index_.end(), 0);
  if (!index_.empty()) root_ = Build(0, static_cast<int>(index_.size()));
}

int KdTree::Nearest(const Vector3d& q, double* distance2) const {
  int best = -1;
  double best_d2 = std::numeric_limits<double>::infinity();
  if (root_ >= 0) Search(root_, q, &best, &best_d2);
  *distance2 = best_d2;
  return best;
}

int KdTree::Build(int begin, int end) {
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

void KdTree::Search(int id, const Vector3d& q, int* best, double* best_d2) const {
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

ScanSamples SampleScan(const Mesh& scan, int count, bool flip_normals) {
  const RowMatrixX3d cross = FaceCrossProducts(scan);
  std::vector<double> cumulative;
  cumulative.reserve(scan.num_faces());
  double total = 0.0;
  for (int f = 0; f < scan.num_faces(); ++f) {
    const double a = cross.row(f).norm();
    total += std::isfinite(a) ? a : 0.0;
    cumulative.push_back(total);
  }
  ScanSamples samples;
  if (!(total > 0)) return samples;
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int i = 0; i < count; ++i) {
    const double r = (i + uniform(rng)) / count * total;  // stratified over the area
    int f = static_cast<int>(std::lower_bound(cumulative.begin(), cumulative.end(), r) - cumulative.begin());
    f = std::min(f, scan.num_faces() - 1);
    double u = uniform(rng), v = uniform(rng);
    if (u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    const Vector3d a = scan.vertices.row(scan.faces(f, 0)), b = scan.vertices.row(scan.faces(f, 1)),
                   c = scan.vertices.row(scan.faces(f, 2));
    const double norm = cross.row(f).norm();
    if (!(norm > 0)) continue;
    samples.points.push_back(a + u * (b - a) + v * (c - a));
    samples.normals.push_back(cross.row(f).transpose() / norm * (flip_normals ? -1.0 : 1.0));
  }
  samples.spacing = std::sqrt(0.5 * total / std::max<std::size_t>(1, samples.points.size()));
  return samples;
}

}  // namespace tracking_internal
}  // namespace confluent
