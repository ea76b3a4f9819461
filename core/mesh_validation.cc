#include "core/mesh_validation.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <sstream>

namespace confluent {
namespace {

// Disjoint sets with path halving.
class UnionFind {
 public:
  explicit UnionFind(int n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  int Find(int i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  void Union(int a, int b) { parent_[Find(a)] = Find(b); }

 private:
  std::vector<int> parent_;
};

// An undirected edge (low, high) and a face using it.
struct EdgeFace {
  int low, high, face;
  bool operator<(const EdgeFace& other) const {
    return low != other.low ? low < other.low : high != other.high ? high < other.high : face < other.face;
  }
};

// True when the face's indices are in range and pairwise distinct.
bool IsProperTriangle(const Mesh& mesh, int f) {
  const int a = mesh.faces(f, 0), b = mesh.faces(f, 1), c = mesh.faces(f, 2);
  const int n = mesh.num_vertices();
  return a >= 0 && b >= 0 && c >= 0 && a < n && b < n && c < n && a != b && b != c && a != c;
}

// Splits each vertex into its fans (groups of incident faces connected through edges at the
// vertex). Sets `corner_node[3f+k]` to the fan id of face f's corner k (-1 for improper faces)
// and returns the vertices with more than one fan.
std::vector<int> ComputeFans(const Mesh& mesh, const std::vector<char>& proper, std::vector<int>* corner_node) {
  const int n = mesh.num_vertices(), m = mesh.num_faces();
  std::vector<int> start(n + 1, 0);
  for (int f = 0; f < m; ++f)
    if (proper[f])
      for (int k = 0; k < 3; ++k) ++start[mesh.faces(f, k) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int> incident(start[n]);  // 3f + k of each corner, grouped by vertex
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int f = 0; f < m; ++f)
    if (proper[f])
      for (int k = 0; k < 3; ++k) incident[fill[mesh.faces(f, k)]++] = 3 * f + k;

  corner_node->assign(static_cast<std::size_t>(m) * 3, -1);
  std::vector<int> non_manifold;
  std::vector<std::pair<int, int>> spokes;  // (other vertex, local corner index)
  std::vector<int> parent, node_of_root;
  int num_nodes = 0;
  for (int v = 0; v < n; ++v) {
    const int count = start[v + 1] - start[v];
    spokes.clear();
    for (int i = 0; i < count; ++i) {
      const int f = incident[start[v] + i] / 3;
      for (int k = 0; k < 3; ++k)
        if (mesh.faces(f, k) != v) spokes.emplace_back(mesh.faces(f, k), i);
    }
    std::sort(spokes.begin(), spokes.end());
    parent.resize(count);
    std::iota(parent.begin(), parent.end(), 0);
    auto find = [&](int i) {
      while (parent[i] != i) i = parent[i] = parent[parent[i]];
      return i;
    };
    // Faces sharing a spoke edge (v, w) belong to the same fan.
    for (std::size_t i = 1; i < spokes.size(); ++i)
      if (spokes[i].first == spokes[i - 1].first) parent[find(spokes[i].second)] = find(spokes[i - 1].second);
    node_of_root.assign(count, -1);
    int fans = 0;
    for (int i = 0; i < count; ++i) {
      int& node = node_of_root[find(i)];
      if (node < 0) {
        node = num_nodes++;
        ++fans;
      }
      (*corner_node)[incident[start[v] + i]] = node;
    }
    if (fans > 1) non_manifold.push_back(v);
  }
  return non_manifold;
}

// Fan node of the corner of face f at vertex v.
int NodeAt(const Mesh& mesh, const std::vector<int>& corner_node, int f, int v) {
  for (int k = 0; k < 3; ++k)
    if (mesh.faces(f, k) == v) return corner_node[3 * f + k];
  return -1;
}

// "label: N (e.g. a, b, c)" for a list of indices.
template <typename T, typename Format>
void AppendList(std::ostringstream* out, const char* label, const std::vector<T>& items, Format format) {
  *out << label << ": " << items.size();
  if (!items.empty()) {
    *out << " (e.g.";
    for (std::size_t i = 0; i < std::min<std::size_t>(items.size(), 5); ++i) *out << (i ? ", " : " ") << format(items[i]);
    if (items.size() > 5) *out << ", ...";
    *out << ")";
  }
  *out << "\n";
}

}  // namespace

MeshReport ValidateMesh(const Mesh& mesh, const MeshValidationOptions& options) {
  MeshReport report;
  const int n = mesh.num_vertices(), m = mesh.num_faces();
  report.num_vertices = n;
  report.num_faces = m;

  for (int v = 0; v < n; ++v)
    if (!mesh.vertices.row(v).allFinite()) report.invalid_vertices.push_back(v);

  // Degenerate faces: bad or repeated indices, or (nearly) zero area.
  std::vector<char> proper(m, 0);
  std::vector<char> referenced(n, 0);
  for (int f = 0; f < m; ++f) {
    for (int k = 0; k < 3; ++k)
      if (mesh.faces(f, k) >= 0 && mesh.faces(f, k) < n) referenced[mesh.faces(f, k)] = 1;
    proper[f] = IsProperTriangle(mesh, f);
    if (!proper[f]) {
      report.degenerate_faces.push_back(f);
      continue;
    }
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2));
    if (0.5 * (b - a).cross(c - a).norm() < options.degenerate_area_m2) report.degenerate_faces.push_back(f);
  }
  for (int v = 0; v < n; ++v)
    if (!referenced[v]) report.unreferenced_vertices.push_back(v);

  // Duplicate faces: the same sorted vertex triple as an earlier face.
  std::vector<std::pair<std::array<int, 3>, int>> keys;
  keys.reserve(m);
  for (int f = 0; f < m; ++f) {
    if (!proper[f]) continue;
    std::array<int, 3> key = {mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2)};
    std::sort(key.begin(), key.end());
    keys.emplace_back(key, f);
  }
  std::sort(keys.begin(), keys.end());
  for (std::size_t i = 1; i < keys.size(); ++i)
    if (keys[i].first == keys[i - 1].first) report.duplicate_faces.push_back(keys[i].second);
  std::sort(report.duplicate_faces.begin(), report.duplicate_faces.end());

  // Edges: boundary (1 face) and non-manifold (> 2 faces).
  std::vector<EdgeFace> edges;
  edges.reserve(static_cast<std::size_t>(m) * 3);
  for (int f = 0; f < m; ++f) {
    if (!proper[f]) continue;
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces(f, k), b = mesh.faces(f, (k + 1) % 3);
      edges.push_back({std::min(a, b), std::max(a, b), f});
    }
  }
  std::sort(edges.begin(), edges.end());
  // Boundary loops: components of the boundary-edge graph, with pinched vertices split into
  // their fans (so a bow-tie has two loops, not one figure eight).
  std::vector<int> corner_node;
  report.non_manifold_vertices = ComputeFans(mesh, proper, &corner_node);
  const int num_nodes = corner_node.empty() ? 0 : *std::max_element(corner_node.begin(), corner_node.end()) + 1;
  UnionFind boundary_sets(num_nodes);
  std::vector<char> on_boundary(num_nodes, 0);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].low == edges[i].low && edges[j].high == edges[i].high) ++j;
    const std::size_t count = j - i;
    if (count == 1) {
      ++report.num_boundary_edges;
      const int a = NodeAt(mesh, corner_node, edges[i].face, edges[i].low);
      const int b = NodeAt(mesh, corner_node, edges[i].face, edges[i].high);
      boundary_sets.Union(a, b);
      on_boundary[a] = on_boundary[b] = 1;
    } else if (count > 2) {
      report.non_manifold_edges.emplace_back(edges[i].low, edges[i].high);
    }
    i = j;
  }
  for (int node = 0; node < num_nodes; ++node)
    if (on_boundary[node] && boundary_sets.Find(node) == node) ++report.num_boundary_loops;

  // Components: faces connected through shared vertices, numbered in face order.
  UnionFind vertex_sets(n);
  for (int f = 0; f < m; ++f)
    for (int k = 1; k < 3; ++k) {
      const int a = mesh.faces(f, 0), b = mesh.faces(f, k);
      if (a >= 0 && b >= 0 && a < n && b < n) vertex_sets.Union(a, b);
    }
  report.component_of_face.assign(m, -1);
  std::vector<int> id_of_root(n, -1);
  for (int f = 0; f < m; ++f) {
    const int a = mesh.faces(f, 0);
    if (a < 0 || a >= n) continue;
    int& id = id_of_root[vertex_sets.Find(a)];
    if (id < 0) id = report.num_components++;
    report.component_of_face[f] = id;
  }
  return report;
}

std::string MeshReport::ToString() const {
  std::ostringstream out;
  auto index = [](int i) { return std::to_string(i); };
  out << "vertices: " << num_vertices << ", faces: " << num_faces << "\n";
  out << "connected components: " << num_components << "\n";
  out << "boundary edges: " << num_boundary_edges << " in " << num_boundary_loops << " loop(s)\n";
  AppendList(&out, "non-manifold edges", non_manifold_edges,
             [](const std::pair<int, int>& e) { return std::to_string(e.first) + "-" + std::to_string(e.second); });
  AppendList(&out, "non-manifold vertices", non_manifold_vertices, index);
  AppendList(&out, "degenerate faces", degenerate_faces, index);
  AppendList(&out, "duplicate faces", duplicate_faces, index);
  AppendList(&out, "unreferenced vertices", unreferenced_vertices, index);
  AppendList(&out, "invalid (non-finite) vertices", invalid_vertices, index);
  out << "manifold: " << (is_manifold() ? "yes" : "no") << ", watertight: " << (is_watertight() ? "yes" : "no")
      << ", clean: " << (is_clean() ? "yes" : "no") << "\n";
  return out.str();
}

}  // namespace confluent
