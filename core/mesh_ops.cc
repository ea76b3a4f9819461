#include "core/mesh_ops.h"

#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace confluent {
namespace {

// A surface of revolution about z: a top pole, rings of (z, radius) from top to bottom, a
// bottom pole. Faces are CCW seen from outside.
Mesh MakeLathe(const std::vector<std::pair<double, double>>& rings, double top_z, double bottom_z, int segments) {
  const int num_rings = static_cast<int>(rings.size());
  Mesh mesh;
  mesh.vertices.resize(2 + num_rings * segments, 3);
  mesh.vertices.row(0) << 0.0, 0.0, top_z;
  for (int i = 0; i < num_rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double theta = 2.0 * M_PI * j / segments;
      mesh.vertices.row(1 + i * segments + j) << rings[i].second * std::cos(theta),
          rings[i].second * std::sin(theta), rings[i].first;
    }
  const int bottom = 1 + num_rings * segments;
  mesh.vertices.row(bottom) << 0.0, 0.0, bottom_z;
  mesh.faces.resize(2 * segments * num_rings, 3);
  auto ring_vertex = [&](int i, int j) { return 1 + i * segments + (j % segments); };
  int f = 0;
  for (int j = 0; j < segments; ++j) mesh.faces.row(f++) << 0, ring_vertex(0, j), ring_vertex(0, j + 1);
  for (int i = 0; i + 1 < num_rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = ring_vertex(i, j), b = ring_vertex(i, j + 1), c = ring_vertex(i + 1, j), d = ring_vertex(i + 1, j + 1);
      mesh.faces.row(f++) << a, c, b;
      mesh.faces.row(f++) << b, c, d;
    }
  for (int j = 0; j < segments; ++j)
    mesh.faces.row(f++) << bottom, ring_vertex(num_rings - 1, j + 1), ring_vertex(num_rings - 1, j);
  return mesh;
}

// Key of the undirected edge (a, b).
std::uint64_t EdgeKey(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

}  // namespace

RowMatrixX3d FaceCrossProducts(const Mesh& mesh) {
  RowMatrixX3d cross(mesh.num_faces(), 3);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2));
    cross.row(f) = (b - a).cross(c - a).transpose();
  }
  return cross;
}

RowMatrixX3d FaceNormals(const Mesh& mesh) {
  RowMatrixX3d normals = FaceCrossProducts(mesh);
  for (int f = 0; f < normals.rows(); ++f) {
    const double length = normals.row(f).norm();
    normals.row(f) = length > 0.0 ? (normals.row(f) / length).eval() : Eigen::RowVector3d::Zero().eval();
  }
  return normals;
}

Eigen::VectorXd FaceAreas(const Mesh& mesh) { return 0.5 * FaceCrossProducts(mesh).rowwise().norm(); }

RowMatrixX3d VertexNormals(const Mesh& mesh) {
  // Summing unnormalised cross products weights each face by its area.
  const RowMatrixX3d cross = FaceCrossProducts(mesh);
  RowMatrixX3d normals = RowMatrixX3d::Zero(mesh.num_vertices(), 3);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) normals.row(mesh.faces(f, k)) += cross.row(f);
  for (int v = 0; v < normals.rows(); ++v) {
    const double length = normals.row(v).norm();
    if (length > 0.0) normals.row(v) /= length;
  }
  return normals;
}

Eigen::AlignedBox3d BoundingBox(const Mesh& mesh) {
  Eigen::AlignedBox3d box;
  for (int v = 0; v < mesh.num_vertices(); ++v) box.extend(mesh.vertices.row(v).transpose());
  return box;
}

double SignedVolume(const Mesh& mesh) {
  // Sum of signed tetrahedra (origin, a, b, c).
  double volume = 0.0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2));
    volume += a.dot(b.cross(c));
  }
  return volume / 6.0;
}

Mesh MakeBox(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner) {
  // Corner i has x from bit 0, y from bit 1, z from bit 2.
  Mesh mesh;
  mesh.vertices.resize(8, 3);
  for (int i = 0; i < 8; ++i)
    mesh.vertices.row(i) << ((i & 1) ? max_corner.x() : min_corner.x()), ((i & 2) ? max_corner.y() : min_corner.y()),
        ((i & 4) ? max_corner.z() : min_corner.z());
  mesh.faces.resize(12, 3);
  mesh.faces << 0, 2, 1, 1, 2, 3,  // -z
      4, 5, 6, 5, 7, 6,            // +z
      0, 1, 5, 0, 5, 4,            // -y
      2, 6, 7, 2, 7, 3,            // +y
      0, 4, 6, 0, 6, 2,            // -x
      1, 3, 7, 1, 7, 5;            // +x
  return mesh;
}

Mesh MakeUvSphere(double radius_m, int rings, int segments) {
  // Interior latitude rings at polar angles i * pi / rings.
  std::vector<std::pair<double, double>> profile;
  for (int i = 1; i < rings; ++i) {
    const double phi = M_PI * i / rings;
    profile.emplace_back(radius_m * std::cos(phi), radius_m * std::sin(phi));
  }
  return MakeLathe(profile, radius_m, -radius_m, segments);
}

Mesh MakeCapsule(double radius_m, double length_m, int rings, int segments) {
  // Top hemisphere down to its equator at +length/2, then the bottom one from -length/2.
  std::vector<std::pair<double, double>> profile;
  const double half = 0.5 * length_m;
  for (int i = 1; i <= rings; ++i) {
    const double phi = 0.5 * M_PI * i / rings;
    profile.emplace_back(half + radius_m * std::cos(phi), radius_m * std::sin(phi));
  }
  for (int i = (length_m > 0.0 ? 0 : 1); i < rings; ++i) {
    const double phi = 0.5 * M_PI + 0.5 * M_PI * i / rings;
    profile.emplace_back(-half + radius_m * std::cos(phi), radius_m * std::sin(phi));
  }
  return MakeLathe(profile, half + radius_m, -half - radius_m, segments);
}

Mesh SubdivideMidpoint(const Mesh& mesh) {
  const int n = mesh.num_vertices(), m = mesh.num_faces();
  const bool colors = mesh.has_colors(), uvs = mesh.has_uvs();
  // New vertex (or uv) per undirected edge, appended after the old ones.
  std::unordered_map<std::uint64_t, int> vertex_of_edge, uv_of_edge;
  vertex_of_edge.reserve(static_cast<std::size_t>(m) * 2);
  if (uvs) uv_of_edge.reserve(static_cast<std::size_t>(m) * 2);
  std::vector<std::pair<int, int>> new_vertices, new_uvs;
  Mesh out;
  out.faces.resize(4 * m, 3);
  if (uvs) out.face_uvs.resize(4 * m, 3);
  auto midpoint = [](std::unordered_map<std::uint64_t, int>* map, std::vector<std::pair<int, int>>* added, int base,
                     int a, int b) {
    const auto inserted = map->emplace(EdgeKey(a, b), base + static_cast<int>(added->size()));
    if (inserted.second) added->emplace_back(a, b);
    return inserted.first->second;
  };
  for (int f = 0; f < m; ++f) {
    const int a = mesh.faces(f, 0), b = mesh.faces(f, 1), c = mesh.faces(f, 2);
    const int ab = midpoint(&vertex_of_edge, &new_vertices, n, a, b);
    const int bc = midpoint(&vertex_of_edge, &new_vertices, n, b, c);
    const int ca = midpoint(&vertex_of_edge, &new_vertices, n, c, a);
    out.faces.block(4 * f, 0, 4, 3) << a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca;
    if (uvs) {
      const int k = static_cast<int>(mesh.uvs.rows());
      const int ua = mesh.face_uvs(f, 0), ub = mesh.face_uvs(f, 1), uc = mesh.face_uvs(f, 2);
      const int uab = midpoint(&uv_of_edge, &new_uvs, k, ua, ub);
      const int ubc = midpoint(&uv_of_edge, &new_uvs, k, ub, uc);
      const int uca = midpoint(&uv_of_edge, &new_uvs, k, uc, ua);
      out.face_uvs.block(4 * f, 0, 4, 3) << ua, uab, uca, uab, ub, ubc, uca, ubc, uc, uab, ubc, uca;
    }
  }
  const int added = static_cast<int>(new_vertices.size());
  out.vertices.resize(n + added, 3);
  out.vertices.topRows(n) = mesh.vertices;
  if (colors) {
    out.colors.resize(n + added, 3);
    out.colors.topRows(n) = mesh.colors;
  }
  for (int i = 0; i < added; ++i) {
    const auto [a, b] = new_vertices[i];
    out.vertices.row(n + i) = 0.5 * (mesh.vertices.row(a) + mesh.vertices.row(b));
    if (colors) out.colors.row(n + i) = 0.5f * (mesh.colors.row(a) + mesh.colors.row(b));
  }
  if (uvs) {
    const int k = static_cast<int>(mesh.uvs.rows());
    out.uvs.resize(k + static_cast<int>(new_uvs.size()), 2);
    out.uvs.topRows(k) = mesh.uvs;
    for (std::size_t i = 0; i < new_uvs.size(); ++i)
      out.uvs.row(k + i) = 0.5 * (mesh.uvs.row(new_uvs[i].first) + mesh.uvs.row(new_uvs[i].second));
  }
  out.texture_path = mesh.texture_path;
  if (mesh.has_face_labels()) {
    out.face_labels.reserve(4 * m);
    for (int f = 0; f < m; ++f) out.face_labels.insert(out.face_labels.end(), 4, mesh.face_labels[f]);
  }
  return out;
}

}  // namespace confluent
