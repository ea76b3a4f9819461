#pragma once
// Generated geometry for the deform tests: closed tubes ("arms") with many rings along their
// length, and helpers to bend, twist and measure them.

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "deform/correspondences.h"

namespace confluent::testing {

// A closed tube along +z from z = 0 to z = length: `rings` + 1 vertex rings of `segments`
// vertices (ring angle offset by `phase_rad`), closed by a fan around a centre vertex at each
// end. CCW outward.
inline Mesh MakeTube(double radius, double length, int rings, int segments, double phase_rad = 0.0) {
  Mesh mesh;
  const int n = (rings + 1) * segments + 2;
  mesh.vertices.resize(n, 3);
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double a = phase_rad + 2.0 * M_PI * s / segments;
      mesh.vertices.row(r * segments + s) << radius * std::cos(a), radius * std::sin(a), length * r / rings;
    }
  const int bottom = n - 2, top = n - 1;
  mesh.vertices.row(bottom) << 0, 0, 0;
  mesh.vertices.row(top) << 0, 0, length;
  std::vector<Eigen::Vector3i> faces;
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const int a = r * segments + s, b = r * segments + (s + 1) % segments;
      const int c = a + segments, d = b + segments;
      faces.emplace_back(a, b, d);
      faces.emplace_back(a, d, c);
    }
  for (int s = 0; s < segments; ++s) {
    faces.emplace_back(bottom, (s + 1) % segments, s);
    faces.emplace_back(top, rings * segments + s, rings * segments + (s + 1) % segments);
  }
  mesh.faces.resize(static_cast<int>(faces.size()), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) mesh.faces.row(f) = faces[f].transpose();
  return mesh;
}

inline Eigen::Vector3d FaceCentroid(const Mesh& mesh, int f) {
  return (mesh.vertices.row(mesh.faces(f, 0)) + mesh.vertices.row(mesh.faces(f, 1)) +
          mesh.vertices.row(mesh.faces(f, 2))).transpose() / 3.0;
}

// The face of `mesh` whose centroid is nearest to `point`.
inline int NearestFace(const Mesh& mesh, const Eigen::Vector3d& point) {
  int best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const double d = (FaceCentroid(mesh, f) - point).squaredNorm();
    if (d < best_d) {
      best_d = d;
      best = f;
    }
  }
  return best;
}

// Pairs at heights `heights` and `angles` around a tube: template face nearest the surface point,
// scan face nearest the same point. Segment "upper" below `joint_z`, "lower" above.
inline Correspondences TubePairs(const Mesh& template_mesh, const Mesh& scan, const std::vector<double>& heights,
                                 int angles, double radius, double joint_z) {
  Correspondences result;
  for (double z : heights)
    for (int k = 0; k < angles; ++k) {
      const double a = 2.0 * M_PI * (k + 0.25) / angles;
      const Eigen::Vector3d p(radius * std::cos(a), radius * std::sin(a), z);
      CorrespondencePair pair;
      pair.template_triangle = NearestFace(template_mesh, p);
      pair.scan_triangle = NearestFace(scan, p);
      pair.segment = z < joint_z ? "upper" : "lower";
      result.pairs.push_back(pair);
    }
  return result;
}

// Rotates every vertex with z > joint_z rigidly by `rotation` about the point (0, 0, joint_z).
inline RowMatrixX3d RotateAbove(const RowMatrixX3d& vertices, double joint_z, const Eigen::Matrix3d& rotation) {
  RowMatrixX3d result = vertices;
  const Eigen::Vector3d joint(0, 0, joint_z);
  for (int v = 0; v < vertices.rows(); ++v)
    if (vertices(v, 2) > joint_z + 1e-12)
      result.row(v) = (rotation * (vertices.row(v).transpose() - joint) + joint).transpose();
  return result;
}

// Centroid of the deformed positions of the vertices whose reference z lies in [z0, z1].
inline Eigen::Vector3d SliceCentre(const RowMatrixX3d& reference, const RowMatrixX3d& deformed, double z0, double z1) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (int v = 0; v < reference.rows(); ++v)
    if (reference(v, 2) >= z0 && reference(v, 2) <= z1 && reference.row(v).head<2>().norm() > 1e-9) {
      sum += deformed.row(v).transpose();
      ++count;
    }
  return sum / std::max(count, 1);
}

// Mean distance of the deformed ring vertices (reference z in [z0, z1]) from their centroid.
inline double SliceRadius(const RowMatrixX3d& reference, const RowMatrixX3d& deformed, double z0, double z1) {
  const Eigen::Vector3d centre = SliceCentre(reference, deformed, z0, z1);
  double sum = 0.0;
  int count = 0;
  for (int v = 0; v < reference.rows(); ++v)
    if (reference(v, 2) >= z0 && reference(v, 2) <= z1 && reference.row(v).head<2>().norm() > 1e-9) {
      sum += (deformed.row(v).transpose() - centre).norm();
      ++count;
    }
  return sum / std::max(count, 1);
}

inline double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

}  // namespace confluent::testing
