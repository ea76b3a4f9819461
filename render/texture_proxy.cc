// The proxy mesh of projective texturing: vertex clustering on a grid, on the mesh's own vertices.

#include "render/texture_proxy.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "core/mesh_ops.h"

namespace confluent::render_internal {

// A coarse proxy of `mesh` for the visibility depth maps, by vertex clustering on a grid: every
// cluster is represented by one of its own vertices (the one nearest the cluster's mean), so the
// proxy's faces index the mesh's vertices and follow them when they move. Faces that collapse are
// dropped, and so are duplicates. The cell size is chosen for about `target_faces` faces; returns
// the faces and, in *deviation_m, the largest distance of a vertex from its representative along
// the vertex normal (how far the proxy's surface can lie in front of the mesh).
RowMatrixX3i ProxyFaces(const Mesh& mesh, int target_faces, double* deviation_m) {
  const int nv = mesh.num_vertices(), nf = mesh.num_faces();
  const double area = FaceAreas(mesh).sum();
  const RowMatrixX3d normals = VertexNormals(mesh);
  const Eigen::Vector3d lo = mesh.vertices.colwise().minCoeff().transpose();
  // About 2 faces per occupied cell of a surface.
  double cell = std::sqrt(area / std::max(1.0, target_faces / 2.0));
  RowMatrixX3i best;
  std::vector<int> representative;
  for (int attempt = 0; attempt < 4 && cell > 0.0; ++attempt) {
    std::unordered_map<std::uint64_t, int> cluster_of_cell;
    std::vector<int> cluster(nv);
    std::vector<Eigen::Vector3d> sums;
    std::vector<int> counts;
    for (int v = 0; v < nv; ++v) {
      const Eigen::Vector3d g = ((mesh.vertices.row(v).transpose() - lo) / cell).array().floor();
      const std::uint64_t key = (static_cast<std::uint64_t>(g.x()) << 42) ^ (static_cast<std::uint64_t>(g.y()) << 21) ^
                                static_cast<std::uint64_t>(g.z());
      const auto [it, inserted] = cluster_of_cell.emplace(key, static_cast<int>(sums.size()));
      if (inserted) {
        sums.push_back(Eigen::Vector3d::Zero());
        counts.push_back(0);
      }
      cluster[v] = it->second;
      sums[it->second] += mesh.vertices.row(v).transpose();
      ++counts[it->second];
    }
    std::vector<int> rep(sums.size(), -1);
    std::vector<double> rep_distance(sums.size(), 1e300);
    for (int v = 0; v < nv; ++v) {
      const int k = cluster[v];
      const double d = (mesh.vertices.row(v).transpose() - sums[k] / counts[k]).squaredNorm();
      if (d < rep_distance[k]) {
        rep_distance[k] = d;
        rep[k] = v;
      }
    }
    std::unordered_set<std::uint64_t> seen;
    std::vector<Eigen::Vector3i> faces;
    for (int f = 0; f < nf; ++f) {
      Eigen::Vector3i r(rep[cluster[mesh.faces(f, 0)]], rep[cluster[mesh.faces(f, 1)]], rep[cluster[mesh.faces(f, 2)]]);
      if (r[0] == r[1] || r[1] == r[2] || r[0] == r[2]) continue;
      // Same face, same orientation: rotate the smallest index first.
      int first = 0;
      for (int k = 1; k < 3; ++k)
        if (r[k] < r[first]) first = k;
      const Eigen::Vector3i c(r[first], r[(first + 1) % 3], r[(first + 2) % 3]);
      const std::uint64_t key = (static_cast<std::uint64_t>(c[0]) << 42) ^ (static_cast<std::uint64_t>(c[1]) << 21) ^
                                static_cast<std::uint64_t>(c[2]);
      if (!seen.insert(key).second) continue;
      faces.push_back(c);
    }
    best.resize(static_cast<Eigen::Index>(faces.size()), 3);
    for (std::size_t f = 0; f < faces.size(); ++f) best.row(static_cast<Eigen::Index>(f)) = faces[f].transpose();
    representative.assign(nv, 0);
    for (int v = 0; v < nv; ++v) representative[v] = rep[cluster[v]];
    const double ratio = static_cast<double>(faces.size()) / target_faces;
    if (ratio < 1.25 && ratio > 0.8) break;
    cell *= std::sqrt(ratio);
  }
  double deviation = 0.0;
  for (int v = 0; v < nv; ++v) {
    const Eigen::Vector3d offset = mesh.vertices.row(representative[v]) - mesh.vertices.row(v);
    deviation = std::max(deviation, std::abs(offset.dot(normals.row(v).transpose())));  // zero normal: 0
  }
  *deviation_m = deviation;
  return best;
}

}  // namespace confluent::render_internal
