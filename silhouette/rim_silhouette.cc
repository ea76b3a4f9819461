#include "silhouette/rim_silhouette.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "silhouette/overlap.h"

namespace confluent {

RimSilhouetteRasterizer::RimSilhouetteRasterizer(const RowMatrixX3i& faces) : faces_(faces) {
  // Every directed edge with its face, sorted, so that an edge's twin is found by search.
  std::vector<std::pair<std::uint64_t, int>> directed;
  directed.reserve(static_cast<std::size_t>(faces.rows()) * 3);
  auto key = [](int from, int to) { return (static_cast<std::uint64_t>(from) << 32) | static_cast<std::uint32_t>(to); };
  for (int f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) directed.push_back({key(faces(f, k), faces(f, (k + 1) % 3)), f});
  std::sort(directed.begin(), directed.end());
  closed_ = !directed.empty();
  for (std::size_t i = 0; i < directed.size() && closed_; ++i) {
    if (i + 1 < directed.size() && directed[i].first == directed[i + 1].first) closed_ = false;  // an edge used twice one way
    const int from = static_cast<int>(directed[i].first >> 32), to = static_cast<int>(directed[i].first & 0xffffffffu);
    if (from == to) closed_ = false;
    const auto twin = std::lower_bound(directed.begin(), directed.end(), std::make_pair(key(to, from), -1));
    if (twin == directed.end() || twin->first != key(to, from)) closed_ = false;
    else if (from < to) edges_.push_back({from, to, directed[i].second, twin->second});
  }
  if (!closed_) edges_.clear();
  // Neighbouring faces are near in memory when the faces are: their facing flags are read in order.
  std::sort(edges_.begin(), edges_.end(), [](const std::array<int, 4>& a, const std::array<int, 4>& b) {
    return std::min(a[2], a[3]) < std::min(b[2], b[3]);
  });
}

Image RimSilhouetteRasterizer::Rasterize(const RowMatrixX3d& vertices, const Camera& camera) const {
  auto fallback = [&] {
    Mesh mesh;
    mesh.vertices = vertices;
    mesh.faces = faces_;
    return RasterizeClosedMesh(mesh, camera);
  };
  if (!closed_) return fallback();
  const int n = static_cast<int>(vertices.rows()), width = camera.width, height = camera.height;
  const double* xyz = vertices.data();  // row-major: x y z per vertex
  const Eigen::Vector3d depth_axis = camera.rotation.row(2).transpose();
  const double depth_offset = camera.translation.z();
  for (int v = 0; v < n; ++v) {
    const double* p = xyz + 3 * v;
    if (!(depth_axis.x() * p[0] + depth_axis.y() * p[1] + depth_axis.z() * p[2] + depth_offset > 0.0)) return fallback();
  }
  // Which triangles face the camera: (b - a) x (c - a) . (a - centre) <= 0, as RasterizeClosedMesh tests.
  const Eigen::Vector3d centre = camera.center_in_world();
  const int num_faces = static_cast<int>(faces_.rows());
  std::vector<char> facing(num_faces);
  const int* corners = faces_.data();
  for (int f = 0; f < num_faces; ++f) {
    const double* a = xyz + 3 * corners[3 * f];
    const double* b = xyz + 3 * corners[3 * f + 1];
    const double* c = xyz + 3 * corners[3 * f + 2];
    const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    const double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
    facing[f] = !(nx * (a[0] - centre.x()) + ny * (a[1] - centre.y()) + nz * (a[2] - centre.z()) > 0.0);
  }
  // Each rim edge, directed as in its facing triangle, adds its direction (+1 down, -1 up) to the
  // winding count of the pixels right of where it crosses a row of pixel centres; rows are
  // half-open (top end in, bottom end out), so a chain of edges crosses each row once.
  std::vector<Eigen::Vector2d> pixels(n);
  std::vector<char> projected(n, 0);
  auto pixel_of = [&](int v) -> const Eigen::Vector2d& {
    if (!projected[v]) camera.ProjectChecked(vertices.row(v).transpose(), &pixels[v]), projected[v] = 1;
    return pixels[v];
  };
  struct Crossing {
    int y, x, direction;
  };
  std::vector<Crossing> crossings;
  int y_min = height, y_max = -1;
  for (const std::array<int, 4>& edge : edges_) {
    if (facing[edge[2]] == facing[edge[3]]) continue;
    const bool forward = facing[edge[2]];
    const Eigen::Vector2d& p = pixel_of(forward ? edge[0] : edge[1]);
    const Eigen::Vector2d& q = pixel_of(forward ? edge[1] : edge[0]);
    if (!p.allFinite() || !q.allFinite() || std::abs(p.x()) > 1e8 || std::abs(p.y()) > 1e8 ||
        std::abs(q.x()) > 1e8 || std::abs(q.y()) > 1e8)
      return fallback();
    if (p.y() == q.y()) continue;
    const int direction = q.y() > p.y() ? 1 : -1;
    const int row0 = std::max(0, static_cast<int>(std::ceil(std::min(p.y(), q.y()))));
    const int row1 = std::min(height - 1, static_cast<int>(std::ceil(std::max(p.y(), q.y()))) - 1);
    const double slope = (q.x() - p.x()) / (q.y() - p.y());
    for (int y = row0; y <= row1; ++y) {
      const double x = p.x() + (y - p.y()) * slope;
      const int first = x <= 0.0 ? 0 : (x >= width ? width : static_cast<int>(std::ceil(x)));
      crossings.push_back({y, first, direction});
    }
    y_min = std::min(y_min, row0);
    y_max = std::max(y_max, row1);
  }
  Image out(width, height, 1);
  if (y_max < y_min) return out;
  // The crossings row by row, left to right; between two crossings the winding is constant.
  std::vector<int> row_start(y_max - y_min + 2, 0);
  for (const Crossing& c : crossings) ++row_start[c.y - y_min + 1];
  for (std::size_t r = 1; r < row_start.size(); ++r) row_start[r] += row_start[r - 1];
  std::vector<std::pair<int, int>> by_row(crossings.size());  // {x, direction}
  {
    std::vector<int> next(row_start.begin(), row_start.end() - 1);
    for (const Crossing& c : crossings) by_row[next[c.y - y_min]++] = {c.x, c.direction};
  }
  for (int y = y_min; y <= y_max; ++y) {
    const auto begin = by_row.begin() + row_start[y - y_min], end = by_row.begin() + row_start[y - y_min + 1];
    std::sort(begin, end);
    std::uint8_t* row = out.data.data() + static_cast<std::size_t>(y) * width;
    int winding = 0;
    for (auto c = begin; c != end; ++c) {
      winding += c->second;
      const int span_end = c + 1 != end ? (c + 1)->first : width;
      if (winding != 0 && span_end > c->first) std::fill(row + c->first, row + span_end, std::uint8_t{255});
    }
  }
  return out;
}

}  // namespace confluent
