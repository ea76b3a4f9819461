#include "export/mesh_decimate.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <vector>

#include "core/error.h"

namespace confluent {

void DecimateOptions::Check() const {
  RequireOption(target_triangles >= 1, "DecimateOptions.target_triangles", target_triangles, ">= 1");
  RequireOption(max_relative_error > 0.0, "DecimateOptions.max_relative_error", max_relative_error, "> 0");
}

SeamSplitMesh DecimateSplitMesh(const SeamSplitMesh& mesh, const RowMatrixX3d& scan_vertices,
                                const DecimateOptions& options, DecimateSummary* summary) {
  options.Check();
  for (int v : mesh.source_vertex) {
    if (v < 0 || v >= scan_vertices.rows()) throw InputError("mesh", "a split vertex's scan vertex is out of range");
  }
  DecimateSummary result;
  result.input_triangles = mesh.num_faces();
  std::vector<unsigned int> indices(mesh.faces.data(), mesh.faces.data() + mesh.faces.size());
  std::vector<unsigned int> kept(indices.size());
  if (mesh.num_faces() > options.target_triangles) {
    // meshoptimizer treats vertices at the same position as one across a seam and lets them
    // slide along it; nudging each further copy of a scan vertex by a negligible distance
    // (1e-6 of the extent) makes the seam a border, which LockBorder keeps in place.
    RowMatrixX3f positions = mesh.Positions(scan_vertices).cast<float>();
    const float nudge = 1e-6f * (positions.colwise().maxCoeff() - positions.colwise().minCoeff()).maxCoeff();
    std::vector<int> copies(scan_vertices.rows(), 0);
    for (int v = 0; v < mesh.num_vertices(); ++v) positions(v, 0) += nudge * copies[mesh.source_vertex[v]]++;
    float error = 0.0f;
    const std::size_t count = meshopt_simplify(
        kept.data(), indices.data(), indices.size(), positions.data(), positions.rows(), sizeof(float) * 3,
        static_cast<std::size_t>(options.target_triangles) * 3, static_cast<float>(options.max_relative_error),
        meshopt_SimplifyLockBorder, &error);
    kept.resize(count);
    result.relative_error = error;
  } else {
    kept = indices;
  }
  // Compact: keep the used vertices in order of first use.
  std::vector<int> new_index(mesh.num_vertices(), -1);
  SeamSplitMesh out;
  out.faces.resize(static_cast<Eigen::Index>(kept.size() / 3), 3);
  for (std::size_t i = 0; i < kept.size(); ++i) {
    int& n = new_index[kept[i]];
    if (n < 0) {
      n = static_cast<int>(out.source_vertex.size());
      out.source_vertex.push_back(mesh.source_vertex[kept[i]]);
    }
    out.faces(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3)) = n;
  }
  out.uvs.resize(out.num_vertices(), 2);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (new_index[v] >= 0) out.uvs.row(new_index[v]) = mesh.uvs.row(v);
  }
  result.output_triangles = out.num_faces();
  result.output_vertices = out.num_vertices();
  if (summary) *summary = result;
  return out;
}

}  // namespace confluent
