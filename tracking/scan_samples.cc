#include "tracking/scan_samples.h"

#include <cmath>
#include <random>

#include "core/mesh_ops.h"

namespace confluent {
namespace tracking_internal {

using Eigen::Vector3d;

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
