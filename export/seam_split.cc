#include "export/seam_split.h"

#include <unordered_map>

#include "core/error.h"

namespace confluent {

RowMatrixX3d SeamSplitMesh::Positions(const RowMatrixX3d& scan_vertices) const {
  RowMatrixX3d positions(num_vertices(), 3);
  for (int i = 0; i < num_vertices(); ++i) positions.row(i) = scan_vertices.row(source_vertex[i]);
  return positions;
}

SeamSplitMesh SplitAtUvSeams(const Mesh& mesh) {
  if (!mesh.has_uvs()) throw InputError("mesh", "has no per-corner texture coordinates (UVs) to split at seams");
  SeamSplitMesh split;
  split.faces.resize(mesh.num_faces(), 3);
  std::unordered_map<long long, int> index_of;  // (scan vertex, uv index) -> split vertex
  index_of.reserve(static_cast<std::size_t>(mesh.num_vertices()) * 2);
  std::vector<int> uv_index;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int v = mesh.faces(f, c);
      const int t = mesh.face_uvs(f, c);
      if (v < 0 || v >= mesh.num_vertices() || t < 0 || t >= mesh.uvs.rows()) {
        throw InputError("mesh", "face " + std::to_string(f) + " has a vertex or UV index out of range");
      }
      const long long key = static_cast<long long>(v) * mesh.uvs.rows() + t;
      const auto [it, inserted] = index_of.emplace(key, split.num_vertices());
      if (inserted) {
        split.source_vertex.push_back(v);
        uv_index.push_back(t);
      }
      split.faces(f, c) = it->second;
    }
  }
  split.uvs.resize(split.num_vertices(), 2);
  for (int i = 0; i < split.num_vertices(); ++i) split.uvs.row(i) = mesh.uvs.row(uv_index[i]);
  return split;
}

}  // namespace confluent
