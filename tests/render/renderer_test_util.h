#pragma once
// Shared generators for the renderer tests: cameras, spheres, discs and planes.

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <utility>

#include "calib/camera.h"
#include "core/mesh.h"

namespace confluent::render_test {

// A camera at `center_in_world` looking at `target_in_world`, world Z up, OpenCV axes.
inline Camera LookAtTestCamera(const Eigen::Vector3d& center_in_world, const Eigen::Vector3d& target_in_world,
                           int width = 160, int height = 120, double focal_px = 150.0) {
  Camera camera;
  camera.name = "test";
  camera.width = width;
  camera.height = height;
  camera.K << focal_px, 0.0, (width - 1) / 2.0 + 3.3, 0.0, focal_px * 1.02, (height - 1) / 2.0 - 2.1, 0.0, 0.0, 1.0;
  const Eigen::Vector3d z = (target_in_world - center_in_world).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  camera.rotation.row(0) = x.transpose();
  camera.rotation.row(1) = y.transpose();
  camera.rotation.row(2) = z.transpose();
  camera.translation = -camera.rotation * center_in_world;
  return camera;
}

// A generic test camera: 160x120, looking at the origin from a non-axis-aligned position.
inline Camera TestCamera(bool with_distortion) {
  Camera camera = LookAtTestCamera(Eigen::Vector3d(1.1, -2.6, 0.9), Eigen::Vector3d(0.02, 0.03, 0.01));
  if (with_distortion) camera.dist << -0.28, 0.09, 0.0012, -0.0009, -0.01;
  return camera;
}

// Icosphere: 20 * 4^subdivisions faces, vertices on the sphere, faces counter-clockwise seen
// from outside.
inline Mesh MakeIcosphere(const Eigen::Vector3d& center, double radius, int subdivisions) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> points = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : points) p.normalize();
  std::vector<Eigen::Vector3i> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                        {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                        {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                        {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<int, int>, int> midpoint;
    auto mid = [&](int a, int b) {
      const std::pair<int, int> key(std::min(a, b), std::max(a, b));
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      points.push_back((points[a] + points[b]).normalized());
      midpoint[key] = static_cast<int>(points.size()) - 1;
      return static_cast<int>(points.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const auto& f : faces) {
      const int ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    faces.swap(next);
  }
  Mesh mesh;
  mesh.vertices.resize(points.size(), 3);
  for (std::size_t i = 0; i < points.size(); ++i) mesh.vertices.row(i) = (center + radius * points[i]).transpose();
  mesh.faces.resize(faces.size(), 3);
  for (std::size_t i = 0; i < faces.size(); ++i) mesh.faces.row(i) = faces[i].transpose();
  return mesh;
}

// A flat disc (triangle fan, `segments` sides) around `center_in_world`, in the plane with
// normal `normal`.
inline Mesh MakeDisc(const Eigen::Vector3d& center_in_world, const Eigen::Vector3d& normal, double radius,
                     int segments = 48) {
  const Eigen::Vector3d n = normal.normalized();
  const Eigen::Vector3d u = n.unitOrthogonal();
  const Eigen::Vector3d v = n.cross(u);
  Mesh mesh;
  mesh.vertices.resize(segments + 1, 3);
  mesh.faces.resize(segments, 3);
  mesh.vertices.row(0) = center_in_world.transpose();
  for (int i = 0; i < segments; ++i) {
    const double angle = 2.0 * M_PI * i / segments;
    mesh.vertices.row(i + 1) = (center_in_world + radius * (std::cos(angle) * u + std::sin(angle) * v)).transpose();
    mesh.faces.row(i) << 0, i + 1, (i + 1) % segments + 1;
  }
  return mesh;
}

// A square of side `size` centred at `center_in_world`, spanned by unit vectors `u` and `v`, with
// UVs (u right, v up) running 0..1 along `u` and `v`.
inline Mesh MakeSquare(const Eigen::Vector3d& center_in_world, const Eigen::Vector3d& u, const Eigen::Vector3d& v,
                       double size) {
  Mesh mesh;
  mesh.vertices.resize(4, 3);
  const double h = size / 2.0;
  mesh.vertices.row(0) = (center_in_world - h * u - h * v).transpose();
  mesh.vertices.row(1) = (center_in_world + h * u - h * v).transpose();
  mesh.vertices.row(2) = (center_in_world + h * u + h * v).transpose();
  mesh.vertices.row(3) = (center_in_world - h * u + h * v).transpose();
  mesh.faces.resize(2, 3);
  mesh.faces << 0, 1, 2, 0, 2, 3;
  mesh.uvs.resize(4, 2);
  mesh.uvs << 0, 0, 1, 0, 1, 1, 0, 1;
  mesh.face_uvs = mesh.faces;
  return mesh;
}

}  // namespace confluent::render_test
