#include "studio/actor.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <unordered_map>

#include "core/error.h"

namespace confluent {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

// Joint indices of the studio skeleton (StudioJointNames order).
enum StudioJoint {
  kPelvis, kSpine, kChest, kNeck, kHead, kHeadEnd,
  kLShoulder, kLElbow, kLWrist, kLHandEnd,
  kRShoulder, kRElbow, kRWrist, kRHandEnd,
  kLHip, kLKnee, kLAnkle, kLToe,
  kRHip, kRKnee, kRAnkle, kRToe,
  kNumStudioJoints
};

// A bone from joint `from` to joint `to`; it is moved by `from` and belongs to `segment`.
struct Bone {
  int from;
  int to;
  BodySegment segment;
};

const std::vector<Bone>& Bones() {
  static const std::vector<Bone> bones = {
      {kPelvis, kSpine, BodySegment::kLowerTorso},     {kSpine, kChest, BodySegment::kUpperTorso},
      {kChest, kNeck, BodySegment::kUpperTorso},       {kNeck, kHead, BodySegment::kNeck},
      {kHead, kHeadEnd, BodySegment::kHead},           {kChest, kLShoulder, BodySegment::kUpperTorso},
      {kLShoulder, kLElbow, BodySegment::kLeftUpperArm}, {kLElbow, kLWrist, BodySegment::kLeftForearm},
      {kLWrist, kLHandEnd, BodySegment::kLeftHand},    {kChest, kRShoulder, BodySegment::kUpperTorso},
      {kRShoulder, kRElbow, BodySegment::kRightUpperArm}, {kRElbow, kRWrist, BodySegment::kRightForearm},
      {kRWrist, kRHandEnd, BodySegment::kRightHand},   {kPelvis, kLHip, BodySegment::kLowerTorso},
      {kLHip, kLKnee, BodySegment::kLeftThigh},        {kLKnee, kLAnkle, BodySegment::kLeftShank},
      {kLAnkle, kLToe, BodySegment::kLeftFoot},        {kPelvis, kRHip, BodySegment::kLowerTorso},
      {kRHip, kRKnee, BodySegment::kRightThigh},       {kRKnee, kRAnkle, BodySegment::kRightShank},
      {kRAnkle, kRToe, BodySegment::kRightFoot},
  };
  return bones;
}

// A tapered capsule with elliptic cross-section: the axis runs from a to b; the cross-section
// radii (along e1 and e2 = axis x e1) go linearly from r_a to r_b; the ends are half-ellipsoids
// with axial radii cap_a and cap_b. a == b gives an ellipsoid (axis = +z).
struct Primitive {
  Vector3d a, b;
  Vector2d r_a, r_b;
  double cap_a, cap_b;
  Vector3d e1_hint;
  double blend_m;  // smooth-union radius with the primitives before it
  BodySegment segment;
  // Derived frame.
  Vector3d axis, e1, e2;
  double length = 0.0;

  void Finish() {
    length = (b - a).norm();
    axis = length > 1e-12 ? Vector3d((b - a) / length) : Vector3d::UnitZ();
    e1 = (e1_hint - e1_hint.dot(axis) * axis).normalized();
    e2 = axis.cross(e1);
  }

  // Approximate signed distance (negative inside), after Quilez's ellipsoid bound.
  double Distance(const Vector3d& p) const {
    const Vector3d d = p - a;
    const double u = d.dot(axis);
    const double t = length > 0.0 ? std::clamp(u / length, 0.0, 1.0) : 0.0;
    const Vector2d r = (1.0 - t) * r_a + t * r_b;
    const double excess = u < 0.0 ? u : (u > length ? u - length : 0.0);
    const double cap = u < 0.0 ? cap_a : cap_b;
    const Vector3d q(d.dot(e1), d.dot(e2), excess);
    const Vector3d radii(r.x(), r.y(), cap);
    const double k0 = q.cwiseQuotient(radii).norm();
    const double k1 = q.cwiseQuotient(radii.cwiseProduct(radii)).norm();
    // Inside, (k0 - 1) * min radius is exact at the centre of a round section; outside,
    // Quilez's k0 (k0 - 1) / k1 bound is accurate near the surface.
    if (k0 <= 1.0 || k1 < 1e-12) return (k0 - 1.0) * radii.minCoeff();
    return k0 * (k0 - 1.0) / k1;
  }

  // Axis-aligned bounds of the primitive.
  void Bounds(Vector3d* lo, Vector3d* hi) const {
    const double r = std::max({r_a.maxCoeff(), r_b.maxCoeff(), cap_a, cap_b});
    *lo = a.cwiseMin(b).array() - r;
    *hi = a.cwiseMax(b).array() + r;
  }
};

// Polynomial smooth minimum (Quilez) with blend radius k.
double SmoothMin(double x, double y, double k) {
  if (k <= 0.0) return std::min(x, y);
  const double h = std::max(k - std::abs(x - y), 0.0) / k;
  return std::min(x, y) - h * h * k * 0.25;
}

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
  const Vector3d head_center = J[kHead] + Vector3d(0.0, 0.01 * s, 0.085 * s);
  // Torso: pelvis, waist, chest, shoulder girdle.
  add(at(0, -0.005, 0.86), at(0, -0.005, 1.02), Vector2d(0.158, 0.105) * gt, Vector2d(0.148, 0.098) * gt,
      0.09 * gt, 0.09 * gt, X, 0.0, BodySegment::kLowerTorso);
  add(at(0, -0.005, 1.02), at(0, -0.01, 1.18), Vector2d(0.143, 0.094) * gt, Vector2d(0.150, 0.100) * gt,
      0.09 * gt, 0.09 * gt, X, 0.05 * gt, BodySegment::kUpperTorso);
  add(at(0, -0.01, 1.18), at(0, -0.015, 1.37), Vector2d(0.155, 0.104) * gt, Vector2d(0.160, 0.100) * gt,
      0.09 * gt, 0.055 * gt, X, 0.05 * gt, BodySegment::kUpperTorso);
  add(J[kLShoulder] + at(0.03, 0, -0.015), J[kRShoulder] + at(-0.03, 0, -0.015), Vector2d(0.055, 0.06) * gt,
      Vector2d(0.055, 0.06) * gt, 0.055 * gt, 0.055 * gt, Vector3d::UnitZ(), 0.05 * gt, BodySegment::kUpperTorso);
  // Neck and head (skull, jaw, nose, ears).
  add(J[kNeck] + at(0, 0, -0.05), J[kHead] + at(0, 0.005, 0.02), Vector2d(0.056, 0.058) * gh,
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
    const int shoulder = side == 0 ? kLShoulder : kRShoulder;
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
    const int hip = side == 0 ? kLHip : kRHip;
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

// Signed field values of the body on a regular grid.
struct Grid {
  Vector3d origin = Vector3d::Zero();
  double cell = 0.0;
  int nx = 0, ny = 0, nz = 0;
  std::vector<float> values;
  std::int64_t Index(int i, int j, int k) const { return i + static_cast<std::int64_t>(nx) * (j + static_cast<std::int64_t>(ny) * k); }
  Vector3d Position(int i, int j, int k) const { return origin + cell * Vector3d(i, j, k); }
};

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

int FindRoot(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

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

// Vertex one-rings in compressed form: neighbours of v are adjacency[offsets[v] .. offsets[v+1]).
struct Adjacency {
  std::vector<int> offsets, neighbors;
};

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

// Lattice value noise in [0, 1] with smooth interpolation.
double Hash(std::int64_t x, std::int64_t y, std::int64_t z, unsigned seed) {
  std::uint64_t h = static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint64_t>(y) * 0xC2B2AE3D27D4EB4Full ^
                    static_cast<std::uint64_t>(z) * 0x165667B19E3779F9ull ^ (static_cast<std::uint64_t>(seed) << 32);
  h ^= h >> 33;
  h *= 0xff51afd7ed558ccdull;
  h ^= h >> 33;
  h *= 0xc4ceb9fe1a85ec53ull;
  h ^= h >> 33;
  return static_cast<double>(h >> 11) / static_cast<double>(1ull << 53);
}

double ValueNoise(const Vector3d& p, unsigned seed) {
  const Eigen::Vector3d fl = p.array().floor();
  const Eigen::Vector3d t = p - fl;
  const Eigen::Vector3d w = t.array() * t.array() * (3.0 - 2.0 * t.array());
  const auto x = static_cast<std::int64_t>(fl.x()), y = static_cast<std::int64_t>(fl.y()), z = static_cast<std::int64_t>(fl.z());
  double result = 0.0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double weight = (dx ? w.x() : 1 - w.x()) * (dy ? w.y() : 1 - w.y()) * (dz ? w.z() : 1 - w.z());
    result += weight * Hash(x + dx, y + dy, z + dz, seed);
  }
  return result;
}

Eigen::Vector3d SrgbToLinear(double r, double g, double b) {
  auto f = [](double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); };
  return Eigen::Vector3d(f(r), f(g), f(b));
}

// Distance from p to the segment [a, b] and the parameter of the closest point.
double SegmentDistance(const Vector3d& p, const Vector3d& a, const Vector3d& b, double* t_out = nullptr) {
  const Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  if (t_out) *t_out = t;
  return (p - (a + t * ab)).norm();
}

// True when x is within half_width of a multiple of period.
bool OnLine(double x, double period, double half_width) {
  const double r = x - period * std::round(x / period);
  return std::abs(r) < half_width;
}

// Procedural albedo (linear RGB) of a rest-pose point.
Eigen::Vector3d Albedo(const Vector3d& p, BodySegment segment, const std::vector<Vector3d>& J, double s,
                       unsigned seed) {
  const Eigen::Vector3d skin = SrgbToLinear(0.87, 0.67, 0.56);
  const Eigen::Vector3d hair = SrgbToLinear(0.22, 0.13, 0.07);
  const Eigen::Vector3d shirt = SrgbToLinear(0.80, 0.20, 0.16);
  const Eigen::Vector3d shirt_line = SrgbToLinear(0.12, 0.14, 0.36);
  const Eigen::Vector3d shirt_thin = SrgbToLinear(0.95, 0.85, 0.55);
  const Eigen::Vector3d denim = SrgbToLinear(0.20, 0.28, 0.50);
  const Eigen::Vector3d white = SrgbToLinear(0.93, 0.93, 0.90);
  const Vector3d q = p / s;  // unit-height coordinates
  Eigen::Vector3d color = skin;
  auto trousers = [&]() {
    Eigen::Vector3d c = denim;
    if (OnLine(q.x() + q.y() + q.z(), 0.012, 0.002)) c *= 0.8;  // fine diagonal twill
    return c;
  };
  switch (segment) {
    case BodySegment::kHead: {
      const Vector3d c = (J[kHead] / s) + Vector3d(0.0, 0.01, 0.085);
      const Vector3d d = q - c;
      const bool face = d.y() > 0.0 && d.z() < 0.03 - 0.3 * std::max(0.0, -d.y());
      color = skin;
      if (!face && d.z() > -0.075 + 0.3 * std::max(0.0, d.y())) color = hair;
      if (d.z() > 0.032 + 0.15 * std::max(0.0, d.y() - 0.05)) color = hair;
      if (d.y() > 0.05) {
        for (double side : {-1.0, 1.0}) {
          const double ex = d.x() - side * 0.032, ez = d.z() - 0.008;
          if (ex * ex / (0.013 * 0.013) + ez * ez / (0.008 * 0.008) < 1.0) color = SrgbToLinear(0.95, 0.95, 0.95);
          if (ex * ex + ez * ez < 0.0055 * 0.0055) color = SrgbToLinear(0.12, 0.22, 0.35);
          if (std::abs(ex) < 0.016 && std::abs(d.z() - 0.027) < 0.0035) color = hair;  // eyebrows
        }
        if (std::abs(d.x()) < 0.024 && std::abs(d.z() + 0.046) < 0.0065) color = SrgbToLinear(0.72, 0.30, 0.30);
      }
      break;
    }
    case BodySegment::kNeck:
      color = skin;
      break;
    case BodySegment::kUpperTorso:
    case BodySegment::kLeftUpperArm:
    case BodySegment::kRightUpperArm: {
      color = shirt;
      // Plaid in surface coordinates: around and along the torso (or the arm).
      double u = 0.0, v = 0.0;
      if (segment == BodySegment::kUpperTorso) {
        u = std::atan2(q.x(), q.y() - J[kChest].y() / s) * 0.15;
        v = q.z();
      } else {
        const int shoulder = segment == BodySegment::kLeftUpperArm ? kLShoulder : kRShoulder;
        const Vector3d axis = (J[shoulder + 1] - J[shoulder]).normalized();
        const Vector3d d = p - J[shoulder];
        const Vector3d ref = (Vector3d::UnitY() - axis.y() * axis).normalized();
        const Vector3d radial = d - d.dot(axis) * axis;
        u = std::atan2(radial.dot(axis.cross(ref)), radial.dot(ref)) * 0.045;
        v = d.dot(axis) / s;
      }
      if (OnLine(u, 0.07, 0.008) || OnLine(v, 0.07, 0.008))
        color = shirt_line;
      else if (OnLine(u + 0.035, 0.07, 0.0025) || OnLine(v + 0.035, 0.07, 0.0025))
        color = shirt_thin;
      if (segment != BodySegment::kUpperTorso) {
        // Short sleeves with a hem; skin below.
        const int shoulder = segment == BodySegment::kLeftUpperArm ? kLShoulder : kRShoulder;
        double t = 0.0;
        SegmentDistance(p, J[shoulder], J[shoulder + 1], &t);
        if (t > 0.62) color = skin;
        else if (t > 0.56) color = shirt_line;
      } else {
        const double chest_y = J[kChest].y() / s;
        if (q.y() > chest_y + 0.04) {
          // Front: a yellow logo on the left chest and a white placket with buttons.
          const double lx = q.x() + 0.085, lz = q.z() - 1.33;
          const double r = std::sqrt(lx * lx + lz * lz);
          if (r < 0.055) color = SrgbToLinear(0.98, 0.82, 0.12);
          if (r < 0.03) color = SrgbToLinear(0.10, 0.45, 0.25);
          if (std::abs(lx) < 0.006 && r < 0.055) color = SrgbToLinear(0.98, 0.98, 0.95);
          if (std::abs(q.x()) < 0.012 && q.z() < 1.40) {
            color = white;
            if (OnLine(q.z() - 1.0, 0.06, 0.006) && std::abs(q.x()) < 0.006) color = SrgbToLinear(0.1, 0.1, 0.1);
          }
        }
        if (q.z() < 1.02) color = shirt_line;  // hem tucked in at the waist
      }
      break;
    }
    case BodySegment::kLeftForearm:
    case BodySegment::kRightForearm: {
      color = skin;
      if (segment == BodySegment::kLeftForearm) {
        double t = 0.0;
        SegmentDistance(p, J[kLElbow], J[kLWrist], &t);
        if (t > 0.82 && t < 0.93) color = SrgbToLinear(0.08, 0.08, 0.08);  // wristwatch
      }
      break;
    }
    case BodySegment::kLeftHand:
    case BodySegment::kRightHand:
      color = skin;
      break;
    case BodySegment::kLowerTorso: {
      color = trousers();
      const double belt_z = q.z() - 0.985;
      if (std::abs(belt_z) < 0.018) {
        color = SrgbToLinear(0.30, 0.18, 0.08);
        if (q.y() > 0.05 && std::abs(q.x()) < 0.03) color = SrgbToLinear(0.85, 0.72, 0.30);
      } else if (q.z() > 1.003) {
        color = shirt_line;
      }
      // Back pockets with orange stitching.
      if (q.y() < -0.05 && q.z() > 0.80 && q.z() < 0.94 && std::abs(q.x()) > 0.035 && std::abs(q.x()) < 0.135) {
        const double ax = std::abs(q.x());
        const bool edge = ax < 0.042 || ax > 0.128 || q.z() > 0.933 || q.z() < 0.807;
        color = edge ? SrgbToLinear(0.92, 0.55, 0.15) : denim * 0.85;
      }
      break;
    }
    case BodySegment::kLeftThigh:
    case BodySegment::kRightThigh:
    case BodySegment::kLeftShank:
    case BodySegment::kRightShank: {
      color = trousers();
      const bool left = segment == BodySegment::kLeftThigh || segment == BodySegment::kLeftShank;
      const int hip = left ? kLHip : kRHip;
      const int a = (segment == BodySegment::kLeftThigh || segment == BodySegment::kRightThigh) ? hip : hip + 1;
      double t = 0.0;
      SegmentDistance(p, J[a], J[a + 1], &t);
      const Vector3d on_axis = J[a] + t * (J[a + 1] - J[a]);
      const Vector3d radial = (p - on_axis).normalized();
      const double outward = left ? -radial.x() : radial.x();
      if (outward > 0.97) color = white;  // side stripe
      if (q.z() < 0.11) color = white;    // socks
      break;
    }
    case BodySegment::kLeftFoot:
    case BodySegment::kRightFoot: {
      color = white;
      const bool left = segment == BodySegment::kLeftFoot;
      const int toe = left ? kLToe : kRToe;
      if (q.y() > J[toe].y() / s - 0.06) color = SrgbToLinear(0.85, 0.12, 0.10);
      if (OnLine(q.y() - q.z() * 1.5, 0.06, 0.008) && q.z() > 0.03) color = SrgbToLinear(0.85, 0.12, 0.10);
      if (q.z() < 0.018) color = SrgbToLinear(0.10, 0.10, 0.10);
      break;
    }
  }
  // Fine detail: two octaves of value noise modulate the brightness by about +-10%.
  const double noise = 0.6 * ValueNoise(q / 0.018, seed) + 0.4 * ValueNoise(q / 0.006, seed + 7);
  return (color * (0.9 + 0.2 * noise)).cwiseMin(1.0);
}

// Skinning weights: for each vertex, the bones adjacent to its nearest bone compete by
// distance; weights per driving joint are diffused over the mesh and cut to 4 influences.
SkinWeights ComputeWeights(const Mesh& mesh, const Adjacency& adjacency, const std::vector<Vector3d>& J,
                           const std::vector<BodySegment>& vertex_segment, double s) {
  const auto& bones = Bones();
  const int n = mesh.num_vertices();
  const int nb = static_cast<int>(bones.size());
  const double sigma = 0.03 * s;
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(n, kNumStudioJoints);
  std::vector<double> d(nb);
  for (int v = 0; v < n; ++v) {
    const Vector3d p = mesh.vertices.row(v).transpose();
    int primary = -1;
    for (int b = 0; b < nb; ++b) {
      d[b] = SegmentDistance(p, J[bones[b].from], J[bones[b].to]);
      if (bones[b].segment == vertex_segment[v] && (primary < 0 || d[b] < d[primary])) primary = b;
    }
    for (int b = 0; b < nb; ++b) {
      const Bone& pb = bones[primary];
      const bool adjacent = bones[b].from == pb.from || bones[b].from == pb.to || bones[b].to == pb.from ||
                            bones[b].to == pb.to;
      if (!adjacent) continue;
      const double x = std::max(0.0, d[b] - d[primary]) / sigma;
      w(v, bones[b].from) = std::max(w(v, bones[b].from), std::exp(-x * x));
    }
    w.row(v) /= w.row(v).sum();
  }
  Eigen::MatrixXd next(n, kNumStudioJoints);
  for (int it = 0; it < 4; ++it) {
    for (int v = 0; v < n; ++v) {
      Eigen::RowVectorXd mean = w.row(v);
      const int begin = adjacency.offsets[v], end = adjacency.offsets[v + 1];
      for (int e = begin; e < end; ++e) mean += w.row(adjacency.neighbors[e]);
      next.row(v) = mean / (1 + end - begin);
    }
    w.swap(next);
  }
  SkinWeights weights;
  weights.joints.setConstant(n, 4, -1);
  weights.weights.setZero(n, 4);
  for (int v = 0; v < n; ++v) {
    std::vector<int> order(kNumStudioJoints);
    std::iota(order.begin(), order.end(), 0);
    std::partial_sort(order.begin(), order.begin() + 4, order.end(), [&](int a, int b) { return w(v, a) > w(v, b); });
    double sum = 0.0;
    for (int k = 0; k < 4; ++k)
      if (w(v, order[k]) > 1e-3) sum += w(v, order[k]);
    for (int k = 0, slot = 0; k < 4; ++k)
      if (w(v, order[k]) > 1e-3) {
        weights.joints(v, slot) = order[k];
        weights.weights(v, slot++) = w(v, order[k]) / sum;
      }
  }
  return weights;
}

}  // namespace

void StudioActorOptions::Check() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v)) throw UsageError(std::string(name) + ": must be positive");
  };
  positive(height_m, "height_m");
  positive(torso_girth, "torso_girth");
  positive(arm_girth, "arm_girth");
  positive(leg_girth, "leg_girth");
  positive(head_size, "head_size");
  if (height_m < 0.5 || height_m > 3.0) throw UsageError("height_m: must be within [0.5, 3] metres");
  for (double g : {torso_girth, arm_girth, leg_girth, head_size})
    if (g < 0.5 || g > 2.0) throw UsageError("girth and head-size factors must be within [0.5, 2]");
  if (!(arm_angle_deg >= 15.0 && arm_angle_deg <= 80.0)) throw UsageError("arm_angle_deg: must be within [15, 80]");
  if (target_triangles < 2000 || target_triangles > 5000000)
    throw UsageError("target_triangles: must be within [2000, 5000000]");
  if (smoothing_iterations < 0 || smoothing_iterations > 200)
    throw UsageError("smoothing_iterations: must be within [0, 200]");
}

std::vector<std::string> StudioJointNames() {
  return {"pelvis", "spine", "chest", "neck", "head", "head_end",
          "left_shoulder", "left_elbow", "left_wrist", "left_hand_end",
          "right_shoulder", "right_elbow", "right_wrist", "right_hand_end",
          "left_hip", "left_knee", "left_ankle", "left_toe",
          "right_hip", "right_knee", "right_ankle", "right_toe"};
}

Skeleton MakeStudioSkeleton(const StudioActorOptions& options) {
  options.Check();
  const double s = options.height_m / 1.75;
  const double angle = options.arm_angle_deg * M_PI / 180.0;
  std::vector<Vector3d> rest(kNumStudioJoints);
  const int parents[kNumStudioJoints] = {-1, kPelvis, kSpine, kChest, kNeck, kHead,
                                         kChest, kLShoulder, kLElbow, kLWrist,
                                         kChest, kRShoulder, kRElbow, kRWrist,
                                         kPelvis, kLHip, kLKnee, kLAnkle,
                                         kPelvis, kRHip, kRKnee, kRAnkle};
  rest[kPelvis] = Vector3d(0, 0, 0.96);
  rest[kSpine] = Vector3d(0, -0.005, 1.10);
  rest[kChest] = Vector3d(0, -0.01, 1.28);
  rest[kNeck] = Vector3d(0, -0.012, 1.455);
  rest[kHead] = Vector3d(0, -0.005, 1.56);
  rest[kHeadEnd] = Vector3d(0, 0.005, 1.75);
  for (int side = 0; side < 2; ++side) {
    const double sx = side == 0 ? -1.0 : 1.0;  // the actor's left is -x
    const int shoulder = side == 0 ? kLShoulder : kRShoulder;
    const Vector3d dir(sx * std::sin(angle), 0.0, -std::cos(angle));
    rest[shoulder] = Vector3d(sx * 0.19, -0.015, 1.425);
    rest[shoulder + 1] = rest[shoulder] + 0.285 * dir;
    rest[shoulder + 2] = rest[shoulder + 1] + 0.25 * dir;
    rest[shoulder + 3] = rest[shoulder + 2] + 0.18 * dir;
    const int hip = side == 0 ? kLHip : kRHip;
    rest[hip] = Vector3d(sx * 0.09, 0.0, 0.91);
    rest[hip + 1] = Vector3d(sx * 0.102, 0.005, 0.49);
    rest[hip + 2] = Vector3d(sx * 0.112, -0.02, 0.085);
    rest[hip + 3] = Vector3d(sx * 0.125, 0.15, 0.02);
  }
  const std::vector<std::string> names = StudioJointNames();
  Skeleton skeleton;
  for (int j = 0; j < kNumStudioJoints; ++j) {
    Joint joint;
    joint.name = names[j];
    joint.parent = parents[j];
    joint.offset_in_parent = (parents[j] < 0 ? rest[j] : Vector3d(rest[j] - rest[parents[j]])) * s;
    skeleton.joints.push_back(joint);
  }
  return skeleton;
}

StudioActor BuildStudioActor(const StudioActorOptions& options) {
  options.Check();
  const double s = options.height_m / 1.75;
  StudioActor actor;
  actor.skeleton = MakeStudioSkeleton(options);
  const std::vector<Vector3d> J = actor.skeleton.RestPositions();
  const std::vector<Primitive> prims = BodyPrimitives(J, options);
  // Marching tetrahedra gives about 2.3e-3 m^2 * (triangles per m^2 ...): calibrated so that
  // triangles ~= kTrianglesCellSquared / cell^2 for the default build.
  const double kTrianglesCellSquared = 15.5;  // triangles * cell^2 (m^2) for the default body
  const double girth = (options.torso_girth + options.arm_girth + options.leg_girth) / 3.0;
  const double cell = std::sqrt(kTrianglesCellSquared * s * s * girth / options.target_triangles);
  // Keep every part at least 2 cells thick so that coarse meshes stay in one piece.
  std::vector<Primitive> meshed = prims;
  for (auto& prim : meshed) {
    const double r_min = cell;
    prim.r_a = prim.r_a.cwiseMax(r_min);
    prim.r_b = prim.r_b.cwiseMax(r_min);
    prim.cap_a = std::max(prim.cap_a, r_min);
    prim.cap_b = std::max(prim.cap_b, r_min);
  }
  Grid grid = SampleField(meshed, cell);
  Mesh mesh = MarchingTetrahedra(grid);
  std::vector<float>().swap(grid.values);
  KeepLargestComponent(&mesh);
  const Adjacency adjacency = VertexAdjacency(mesh);
  TaubinSmooth(adjacency, options.smoothing_iterations, &mesh.vertices);
  // Segments: the primitive that is closest (most inside) at each vertex.
  const int n = mesh.num_vertices();
  std::vector<BodySegment> vertex_segment(n);
  for (int v = 0; v < n; ++v) {
    const Vector3d p = mesh.vertices.row(v).transpose();
    double best = 1e9;
    for (const auto& prim : prims) {
      const double d = prim.Distance(p);
      if (d < best) {
        best = d;
        vertex_segment[v] = prim.segment;
      }
    }
  }
  mesh.face_labels.resize(mesh.num_faces());
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const BodySegment a = vertex_segment[mesh.faces(f, 0)], b = vertex_segment[mesh.faces(f, 1)],
                      c = vertex_segment[mesh.faces(f, 2)];
    mesh.face_labels[f] = static_cast<int>(b == c ? b : a);
  }
  mesh.colors.resize(n, 3);
  for (int v = 0; v < n; ++v)
    mesh.colors.row(v) =
        Albedo(mesh.vertices.row(v).transpose(), vertex_segment[v], J, s, options.seed).cast<float>().transpose();
  actor.weights = ComputeWeights(mesh, adjacency, J, vertex_segment, s);
  actor.mesh = std::move(mesh);
  actor.segment_joint = StudioSegmentJoints();
  return actor;
}

std::array<int, kNumBodySegments> StudioSegmentJoints() {
  return {kHead, kNeck, kSpine, kPelvis, kLShoulder, kLElbow, kLWrist, kRShoulder,
          kRElbow, kRWrist, kLHip, kLKnee, kLAnkle, kRHip, kRKnee, kRAnkle};
}

}  // namespace confluent
