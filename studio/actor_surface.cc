// The studio actor's surface: an implicit body of tapered capsules blended by a smooth minimum,
// sampled on a grid, meshed by marching tetrahedra, reduced to its largest component and
// smoothed (Taubin 1995).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <unordered_map>

#include "studio/actor_internal.h"

namespace confluent::actor_internal {
namespace {

// Polynomial smooth minimum (Quilez) with blend radius k.
double SmoothMin(double x, double y, double k) {
  if (k <= 0.0) return std::min(x, y);
  const double h = std::max(k - std::abs(x - y), 0.0) / k;
  return std::min(x, y) - h * h * k * 0.25;
}

}  // namespace

// The body's primitives for the given skeleton rest positions and options.
std::vector<Primitive> BodyPrimitives(const std::vector<Vector3d>& J, const StudioActorOptions& options) {
  const double s = options.height_m / 1.75;
  const double gt = s * options.torso_girth, ga = s * options.arm_girth, gl = s * options.leg_girth;
  const double gh = s * options.head_size;
  const Vector3d X = Vector3d::UnitX(), Y = Vector3d::UnitY();
  std::vector<Primitive> prims;
  auto add = [&](Vector3d a, Vector3d b, Vector2d ra, Vector2d rb, double ca, double cb, Vector3d e1,
                 double blend, BodySegment segment) {
    Primitive p{a, b, ra, rb, ca, cb, e1, blend, segment, {}, {}, {}, 0.0};
    p.Finish();
    prims.push_back(p);
  };
  auto at = [&](double x, double y, double z) -> Vector3d { return Vector3d(x, y, z) * s; };
  const Vector3d head_center = J[kJointHead] + Vector3d(0.0, 0.01 * s, 0.085 * s);
  // Torso: pelvis, waist, chest, shoulder girdle.
  add(at(0, -0.005, 0.86), at(0, -0.005, 1.02), Vector2d(0.158, 0.105) * gt, Vector2d(0.148, 0.098) * gt,
      0.09 * gt, 0.09 * gt, X, 0.0, BodySegment::kLowerTorso);
  add(at(0, -0.005, 1.02), at(0, -0.01, 1.18), Vector2d(0.143, 0.094) * gt, Vector2d(0.150, 0.100) * gt,
      0.09 * gt, 0.09 * gt, X, 0.05 * gt, BodySegment::kUpperTorso);
  add(at(0, -0.01, 1.18), at(0, -0.015, 1.37), Vector2d(0.155, 0.104) * gt, Vector2d(0.160, 0.100) * gt,
      0.09 * gt, 0.055 * gt, X, 0.05 * gt, BodySegment::kUpperTorso);
  add(J[kJointLeftShoulder] + at(0.03, 0, -0.015), J[kJointRightShoulder] + at(-0.03, 0, -0.015), Vector2d(0.055, 0.06) * gt,
      Vector2d(0.055, 0.06) * gt, 0.055 * gt, 0.055 * gt, Vector3d::UnitZ(), 0.05 * gt, BodySegment::kUpperTorso);
  // Neck and head (skull, jaw, nose, ears).
  add(J[kJointNeck] + at(0, 0, -0.05), J[kJointHead] + at(0, 0.005, 0.02), Vector2d(0.056, 0.058) * gh,
      Vector2d(0.052, 0.054) * gh, 0.05 * gh, 0.05 * gh, X, 0.035 * gh, BodySegment::kNeck);
  add(head_center, head_center, Vector2d(0.078, 0.097) * gh, Vector2d(0.078, 0.097) * gh, 0.106 * gh,
      0.106 * gh, X, 0.03 * gh, BodySegment::kHead);
  add(head_center + Vector3d(0, 0.028, -0.06) * gh, head_center + Vector3d(0, 0.028, -0.06) * gh,
      Vector2d(0.058, 0.062) * gh, Vector2d(0.058, 0.062) * gh, 0.05 * gh, 0.05 * gh, X, 0.03 * gh,
      BodySegment::kHead);
  add(head_center + Vector3d(0, 0.096, -0.012) * gh, head_center + Vector3d(0, 0.102, -0.03) * gh,
      Vector2d(0.011, 0.012) * gh, Vector2d(0.016, 0.016) * gh, 0.012 * gh, 0.014 * gh, X, 0.012 * gh,
      BodySegment::kHead);
  for (double side : {-1.0, 1.0})
    add(head_center + Vector3d(side * 0.074, -0.005, -0.005) * gh,
        head_center + Vector3d(side * 0.074, -0.005, -0.005) * gh, Vector2d(0.014, 0.024) * gh,
        Vector2d(0.014, 0.024) * gh, 0.032 * gh, 0.032 * gh, X, 0.01 * gh, BodySegment::kHead);
  // Arms and hands.
  for (int side = 0; side < 2; ++side) {
    const int shoulder = side == 0 ? kJointLeftShoulder : kJointRightShoulder;
    const int elbow = shoulder + 1, wrist = shoulder + 2, hand_end = shoulder + 3;
    const BodySegment upper = side == 0 ? BodySegment::kLeftUpperArm : BodySegment::kRightUpperArm;
    const BodySegment fore = side == 0 ? BodySegment::kLeftForearm : BodySegment::kRightForearm;
    const BodySegment hand = side == 0 ? BodySegment::kLeftHand : BodySegment::kRightHand;
    add(J[shoulder], J[elbow], Vector2d(0.053, 0.053) * ga, Vector2d(0.04, 0.042) * ga, 0.05 * ga, 0.04 * ga, Y,
        0.025 * ga, upper);
    add(J[elbow], J[wrist], Vector2d(0.041, 0.043) * ga, Vector2d(0.028, 0.022) * ga, 0.04 * ga, 0.025 * ga, Y,
        0.015 * ga, fore);
    const Vector3d dir = (J[hand_end] - J[wrist]).normalized();
    add(J[wrist] + 0.015 * s * dir, J[hand_end] - 0.03 * s * dir, Vector2d(0.037, 0.016) * ga,
        Vector2d(0.04, 0.012) * ga, 0.02 * ga, 0.03 * ga, Y, 0.012 * ga, hand);
    // Thumb, on the front (+y) side of the hand.
    add(J[wrist] + 0.03 * s * dir + Vector3d(0, 0.028, 0) * ga, J[wrist] + 0.085 * s * dir + Vector3d(0, 0.045, 0) * ga,
        Vector2d(0.011, 0.011) * ga, Vector2d(0.009, 0.009) * ga, 0.01 * ga, 0.01 * ga, Y, 0.008 * ga, hand);
  }
  // Legs and feet.
  for (int side = 0; side < 2; ++side) {
    const int hip = side == 0 ? kJointLeftHip : kJointRightHip;
    const int knee = hip + 1, ankle = hip + 2, toe = hip + 3;
    const BodySegment thigh = side == 0 ? BodySegment::kLeftThigh : BodySegment::kRightThigh;
    const BodySegment shank = side == 0 ? BodySegment::kLeftShank : BodySegment::kRightShank;
    const BodySegment foot = side == 0 ? BodySegment::kLeftFoot : BodySegment::kRightFoot;
    add(J[hip] + at(0, 0, 0.02), J[knee], Vector2d(0.088, 0.09) * gl, Vector2d(0.056, 0.058) * gl, 0.08 * gl,
        0.055 * gl, X, 0.045 * gl, thigh);
    add(J[knee], J[ankle], Vector2d(0.052, 0.054) * gl, Vector2d(0.035, 0.037) * gl, 0.05 * gl, 0.035 * gl, X,
        0.02 * gl, shank);
    const Vector3d calf = J[knee] + 0.3 * (J[ankle] - J[knee]) + at(0, -0.018, 0);
    add(calf + at(0, 0, 0.06), calf - at(0, 0, 0.06), Vector2d(0.05, 0.052) * gl, Vector2d(0.045, 0.045) * gl,
        0.05 * gl, 0.07 * gl, X, 0.03 * gl, shank);
    const Vector3d heel(J[ankle].x(), J[ankle].y() - 0.035 * s, 0.045 * s);
    const Vector3d toe_point(J[toe].x(), J[toe].y() - 0.025 * s, 0.037 * s);
    add(heel, toe_point, Vector2d(0.037 * gl, 0.04 * s), Vector2d(0.045 * gl, 0.032 * s), 0.04 * s, 0.045 * s, X,
        0.03 * gl, foot);
  }
  return prims;
}

Grid SampleField(const std::vector<Primitive>& prims, double cell) {
  Vector3d lo = Vector3d::Constant(1e9), hi = Vector3d::Constant(-1e9);
  for (const auto& p : prims) {
    Vector3d a, b;
    p.Bounds(&a, &b);
    lo = lo.cwiseMin(a);
    hi = hi.cwiseMax(b);
  }
  const double margin = 3.0 * cell;
  Grid grid;
  grid.cell = cell;
  grid.origin = lo.array() - margin;
  grid.nx = static_cast<int>(std::ceil((hi.x() - lo.x() + 2 * margin) / cell)) + 1;
  grid.ny = static_cast<int>(std::ceil((hi.y() - lo.y() + 2 * margin) / cell)) + 1;
  grid.nz = static_cast<int>(std::ceil((hi.z() - lo.z() + 2 * margin) / cell)) + 1;
  // Far from every primitive the field only needs to be positive.
  const double far_m = 0.05;
  grid.values.assign(static_cast<std::size_t>(grid.nx) * grid.ny * grid.nz, static_cast<float>(far_m));
  std::vector<double> acc(grid.values.size(), far_m);
  for (const auto& prim : prims) {
    Vector3d a, b;
    prim.Bounds(&a, &b);
    const double reach = 2.0 * (far_m + prim.blend_m);
    auto index_lo = [&](double v, double o) { return std::max(0, static_cast<int>(std::floor((v - reach - o) / cell))); };
    const int i0 = index_lo(a.x(), grid.origin.x()), j0 = index_lo(a.y(), grid.origin.y()),
              k0 = index_lo(a.z(), grid.origin.z());
    const int i1 = std::min(grid.nx - 1, static_cast<int>(std::ceil((b.x() + reach - grid.origin.x()) / cell)));
    const int j1 = std::min(grid.ny - 1, static_cast<int>(std::ceil((b.y() + reach - grid.origin.y()) / cell)));
    const int k1 = std::min(grid.nz - 1, static_cast<int>(std::ceil((b.z() + reach - grid.origin.z()) / cell)));
    for (int k = k0; k <= k1; ++k)
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          double& v = acc[grid.Index(i, j, k)];
          v = SmoothMin(v, prim.Distance(grid.Position(i, j, k)), prim.blend_m);
        }
  }
  for (std::size_t n = 0; n < acc.size(); ++n) {
    float v = static_cast<float>(std::min(acc[n], far_m));
    if (v == 0.0f) v = 1e-7f;  // no grid node exactly on the surface: the level set stays manifold
    grid.values[n] = v;
  }
  return grid;
}

// Marching tetrahedra on the Freudenthal (Kuhn) subdivision of every cube: 6 tetrahedra along
// the main diagonal, consistent across neighbouring cubes. The level set of the piecewise-linear
// field is a closed 2-manifold when the field is positive on the grid boundary and no node is
// exactly zero; vertices are shared through their grid edge.
Mesh MarchingTetrahedra(const Grid& grid) {
  Mesh mesh;
  std::vector<Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
  std::unordered_map<std::int64_t, int> edge_vertex;
  edge_vertex.reserve(1 << 18);
  static const int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  auto corner_node = [&](int i, int j, int k, int bits) {
    return grid.Index(i + (bits & 1), j + ((bits >> 1) & 1), k + ((bits >> 2) & 1));
  };
  auto corner_pos = [&](int i, int j, int k, int bits) {
    return grid.Position(i + (bits & 1), j + ((bits >> 1) & 1), k + ((bits >> 2) & 1));
  };
  for (int k = 0; k + 1 < grid.nz; ++k)
    for (int j = 0; j + 1 < grid.ny; ++j)
      for (int i = 0; i + 1 < grid.nx; ++i) {
        float f[8];
        int inside = 0;
        for (int c = 0; c < 8; ++c) {
          f[c] = grid.values[corner_node(i, j, k, c)];
          inside += f[c] < 0.0f;
        }
        if (inside == 0 || inside == 8) continue;
        // Vertex on the grid edge between corners ca and cb (cb's bits contain ca's).
        auto edge = [&](int ca, int cb) {
          if ((ca & cb) != ca) std::swap(ca, cb);
          const std::int64_t key = corner_node(i, j, k, ca) * 8 + (cb - ca);
          auto [it, inserted] = edge_vertex.try_emplace(key, static_cast<int>(vertices.size()));
          if (inserted) {
            const double t = std::clamp(static_cast<double>(f[ca]) / (static_cast<double>(f[ca]) - f[cb]), 0.03, 0.97);
            vertices.push_back(corner_pos(i, j, k, ca) + t * (corner_pos(i, j, k, cb) - corner_pos(i, j, k, ca)));
          }
          return it->second;
        };
        for (const auto& perm : kPerm) {
          int c[4];
          c[0] = 0;
          c[1] = c[0] | (1 << perm[0]);
          c[2] = c[1] | (1 << perm[1]);
          c[3] = 7;
          int in[4], out[4], n_in = 0, n_out = 0;
          for (int v = 0; v < 4; ++v) (f[c[v]] < 0.0f ? in[n_in++] : out[n_out++]) = c[v];
          if (n_in == 0 || n_out == 0) continue;
          Vector3d in_center = Vector3d::Zero(), out_center = Vector3d::Zero();
          for (int v = 0; v < n_in; ++v) in_center += corner_pos(i, j, k, in[v]) / n_in;
          for (int v = 0; v < n_out; ++v) out_center += corner_pos(i, j, k, out[v]) / n_out;
          const Vector3d outward = out_center - in_center;
          auto emit = [&](int a, int b, int c2) {
            const Vector3d normal = (vertices[b] - vertices[a]).cross(vertices[c2] - vertices[a]);
            faces.push_back(normal.dot(outward) >= 0.0 ? Eigen::Vector3i(a, b, c2) : Eigen::Vector3i(a, c2, b));
          };
          if (n_in == 1) {
            emit(edge(in[0], out[0]), edge(in[0], out[1]), edge(in[0], out[2]));
          } else if (n_out == 1) {
            emit(edge(out[0], in[0]), edge(out[0], in[1]), edge(out[0], in[2]));
          } else {
            const int ac = edge(in[0], out[0]), ad = edge(in[0], out[1]);
            const int bd = edge(in[1], out[1]), bc = edge(in[1], out[0]);
            emit(ac, ad, bd);
            emit(ac, bd, bc);
          }
        }
      }
  mesh.vertices.resize(static_cast<int>(vertices.size()), 3);
  for (std::size_t v = 0; v < vertices.size(); ++v) mesh.vertices.row(static_cast<int>(v)) = vertices[v].transpose();
  mesh.faces.resize(static_cast<int>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) mesh.faces.row(static_cast<int>(f)) = faces[f].transpose();
  return mesh;
}

namespace {

int FindRoot(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

}  // namespace

// Keeps only the connected component with the most faces; renumbers vertices.
void KeepLargestComponent(Mesh* mesh) {
  const int n = mesh->num_vertices();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (int f = 0; f < mesh->num_faces(); ++f)
    for (int c = 1; c < 3; ++c) {
      const int a = FindRoot(parent, mesh->faces(f, 0)), b = FindRoot(parent, mesh->faces(f, c));
      if (a != b) parent[a] = b;
    }
  std::vector<int> count(n, 0);
  for (int f = 0; f < mesh->num_faces(); ++f) ++count[FindRoot(parent, mesh->faces(f, 0))];
  const int best = static_cast<int>(std::max_element(count.begin(), count.end()) - count.begin());
  std::vector<int> remap(n, -1);
  int kept_vertices = 0, kept_faces = 0;
  for (int v = 0; v < n; ++v)
    if (FindRoot(parent, v) == best) remap[v] = kept_vertices++;
  RowMatrixX3d vertices(kept_vertices, 3);
  for (int v = 0; v < n; ++v)
    if (remap[v] >= 0) vertices.row(remap[v]) = mesh->vertices.row(v);
  RowMatrixX3i faces(count[best], 3);
  for (int f = 0; f < mesh->num_faces(); ++f)
    if (FindRoot(parent, mesh->faces(f, 0)) == best)
      faces.row(kept_faces++) << remap[mesh->faces(f, 0)], remap[mesh->faces(f, 1)], remap[mesh->faces(f, 2)];
  mesh->vertices = std::move(vertices);
  mesh->faces = std::move(faces);
}

Adjacency VertexAdjacency(const Mesh& mesh) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(static_cast<std::size_t>(mesh.num_faces()) * 6);
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 3; ++c) {
      const int a = mesh.faces(f, c), b = mesh.faces(f, (c + 1) % 3);
      edges.emplace_back(a, b);
      edges.emplace_back(b, a);
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  Adjacency adjacency;
  adjacency.offsets.assign(mesh.num_vertices() + 1, 0);
  for (const auto& e : edges) ++adjacency.offsets[e.first + 1];
  std::partial_sum(adjacency.offsets.begin(), adjacency.offsets.end(), adjacency.offsets.begin());
  adjacency.neighbors.reserve(edges.size());
  for (const auto& e : edges) adjacency.neighbors.push_back(e.second);
  return adjacency;
}

// Taubin's lambda|mu smoothing (Taubin 1995) with umbrella weights: smooths without shrinking.
void TaubinSmooth(const Adjacency& adjacency, int iterations, RowMatrixX3d* vertices) {
  const int n = static_cast<int>(vertices->rows());
  RowMatrixX3d next(n, 3);
  for (int it = 0; it < 2 * iterations; ++it) {
    const double factor = it % 2 == 0 ? 0.5 : -0.53;
    for (int v = 0; v < n; ++v) {
      Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
      const int begin = adjacency.offsets[v], end = adjacency.offsets[v + 1];
      for (int e = begin; e < end; ++e) mean += vertices->row(adjacency.neighbors[e]);
      mean /= std::max(1, end - begin);
      next.row(v) = vertices->row(v) + factor * (mean - vertices->row(v));
    }
    vertices->swap(next);
  }
}

}  // namespace confluent::actor_internal
