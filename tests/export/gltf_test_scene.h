#pragma once
// Inputs for the glTF and player tests: a UV sphere with a real UV seam (u wraps), a few frames
// of motion, per-frame textures, a camera, and where the npm tools and Chromium are.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "core/mesh_ops.h"
#include "tests/export/player_test_tools.h"

namespace confluent::testing {

// A UV sphere of radius 0.5 m with per-corner UVs in [0, 1]: u = longitude (a seam where it
// wraps), v = latitude; corners of one vertex share a UV index except across the seam.
inline Mesh TexturedSphere(int rings = 16, int segments = 24) {
  Mesh mesh = MakeUvSphere(0.5, rings, segments);
  const double scale = 1.0 / (1.0 + 1.0 / segments);  // u spans [0, 1 + 1/segments] before it
  std::map<std::pair<int, long>, int> uv_index;
  std::vector<Eigen::Vector2d> uvs;
  mesh.face_uvs.resize(mesh.num_faces(), 3);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    double u[3], v[3];
    bool pole[3];
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d p = mesh.vertices.row(mesh.faces(f, c)).transpose() / 0.5;
      pole[c] = std::hypot(p.x(), p.y()) < 1e-9;
      u[c] = pole[c] ? 0.0 : std::atan2(p.y(), p.x()) / (2 * M_PI) + 0.5;
      v[c] = 1.0 - std::acos(std::clamp(p.z(), -1.0, 1.0)) / M_PI;
    }
    double lo = 1, hi = 0;
    for (int c = 0; c < 3; ++c) if (!pole[c]) lo = std::min(lo, u[c]), hi = std::max(hi, u[c]);
    for (int c = 0; c < 3; ++c) if (!pole[c] && hi - lo > 0.5 && u[c] < 0.5) u[c] += 1.0;
    double mean = 0;
    int count = 0;
    for (int c = 0; c < 3; ++c) if (!pole[c]) mean += u[c], ++count;
    for (int c = 0; c < 3; ++c) {
      if (pole[c]) u[c] = mean / count;
      const Eigen::Vector2d uv(u[c] * scale, v[c]);
      const auto key = std::make_pair(mesh.faces(f, c), std::lround(uv.x() * 1e6));
      const auto [it, inserted] = uv_index.emplace(key, static_cast<int>(uvs.size()));
      if (inserted) uvs.push_back(uv);
      mesh.face_uvs(f, c) = it->second;
    }
  }
  mesh.uvs.resize(static_cast<Eigen::Index>(uvs.size()), 2);
  for (std::size_t i = 0; i < uvs.size(); ++i) mesh.uvs.row(i) = uvs[i].transpose();
  return mesh;
}

// Frame k of a moving, breathing sphere: it rises 5 cm per frame and swells along x.
inline std::vector<RowMatrixX3d> SphereFrames(const Mesh& sphere, int frames) {
  std::vector<RowMatrixX3d> out;
  for (int k = 0; k < frames; ++k) {
    RowMatrixX3d v = sphere.vertices;
    v.col(0) *= 1.0 + 0.08 * std::sin(0.9 * k);
    v.col(2).array() += 0.05 * k + 0.03 * (4.0 * v.col(0).array()).sin();
    v.col(1).array() += 0.1;
    out.push_back(v);
  }
  return out;
}

// The atlas of frame k: smooth bands whose phase moves with k (no texel darker than 28, so a
// black background marks the silhouette).
inline Image SphereTexture(int k, int width = 256, int height = 128) {
  Image image(width, height, 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double r = 140 + 100 * std::sin(2 * M_PI * (x / 64.0 + k / 6.0));
      const double g = 140 + 100 * std::cos(2 * M_PI * (y / 32.0 - k / 9.0));
      const double b = 90 + 60 * std::sin(2 * M_PI * (x + y) / 96.0);
      image.at<std::uint8_t>(x, y, 0) = static_cast<std::uint8_t>(std::clamp(r, 28.0, 255.0));
      image.at<std::uint8_t>(x, y, 1) = static_cast<std::uint8_t>(std::clamp(g, 28.0, 255.0));
      image.at<std::uint8_t>(x, y, 2) = static_cast<std::uint8_t>(std::clamp(b, 28.0, 255.0));
    }
  }
  return image;
}

// A 320 x 240 camera 2.4 m from `target`, looking at it from `direction` (world, Z up), with
// an off-centre principal point and unequal focal lengths.
inline Camera LookAtCamera(const Eigen::Vector3d& target, const Eigen::Vector3d& direction) {
  Camera camera = confluent::LookAtCamera("test", target + 2.4 * direction.normalized(), target, 320, 240, 290.0);
  camera.K(1, 1) = 282.0;
  camera.K(0, 2) = 148.5;
  camera.K(1, 2) = 131.25;
  return camera;
}

}  // namespace confluent::testing
