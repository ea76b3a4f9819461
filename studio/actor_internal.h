#pragma once
// INTERNAL (studio/actor*.cc only): the pieces BuildStudioActor (actor.cc) assembles: the studio
// skeleton's joints and bones, the implicit body and its meshing (actor_surface.cc), and the
// procedural albedo (actor_albedo.cc).

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/body_model.h"
#include "studio/actor.h"

namespace confluent::actor_internal {

using Eigen::Vector2d;
using Eigen::Vector3d;

// A bone from joint `from` to joint `to`; it is moved by `from` and belongs to `segment`.
struct Bone {
  int from;
  int to;
  BodySegment segment;
};

// The studio skeleton's bones (actor.cc).
const std::vector<Bone>& Bones();

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
// The body's primitives for the given skeleton rest positions and options.
std::vector<Primitive> BodyPrimitives(const std::vector<Vector3d>& J, const StudioActorOptions& options);

// Signed field values of the body on a regular grid.
struct Grid {
  Vector3d origin = Vector3d::Zero();
  double cell = 0.0;
  int nx = 0, ny = 0, nz = 0;
  std::vector<float> values;
  std::int64_t Index(int i, int j, int k) const { return i + static_cast<std::int64_t>(nx) * (j + static_cast<std::int64_t>(ny) * k); }
  Vector3d Position(int i, int j, int k) const { return origin + cell * Vector3d(i, j, k); }
};

// Samples the primitives' smooth-minimum field on a grid of `cell` metres around the body.
Grid SampleField(const std::vector<Primitive>& prims, double cell);

// Marching tetrahedra on the Freudenthal (Kuhn) subdivision of every cube: 6 tetrahedra along
// the main diagonal, consistent across neighbouring cubes. The level set of the piecewise-linear
// field is a closed 2-manifold when the field is positive on the grid boundary and no node is
// exactly zero; vertices are shared through their grid edge.
Mesh MarchingTetrahedra(const Grid& grid);

// Keeps only the connected component with the most faces; renumbers vertices.
void KeepLargestComponent(Mesh* mesh);

// Vertex one-rings in compressed form: neighbours of v are adjacency[offsets[v] .. offsets[v+1]).
struct Adjacency {
  std::vector<int> offsets, neighbors;
};

// The vertex one-rings of `mesh`.
Adjacency VertexAdjacency(const Mesh& mesh);

// Taubin's lambda|mu smoothing (Taubin 1995) with umbrella weights: smooths without shrinking.
void TaubinSmooth(const Adjacency& adjacency, int iterations, RowMatrixX3d* vertices);

// Distance from p to the segment [a, b] and the parameter of the closest point (actor.cc; there
// t_out defaults to null).
double SegmentDistance(const Vector3d& p, const Vector3d& a, const Vector3d& b, double* t_out);

// Procedural albedo (linear RGB) of a rest-pose point (actor_albedo.cc).
Eigen::Vector3d Albedo(const Vector3d& p, BodySegment segment, const std::vector<Vector3d>& J, double s,
                       unsigned seed);

}  // namespace confluent::actor_internal
