#include "export/uv_atlas.h"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "export/uv_atlas_packing.h"

namespace confluent {

namespace {

using uv_atlas_internal::Chart;
using uv_atlas_internal::OrientChart;
using uv_atlas_internal::Pack;

// Per face: its three neighbours across edges (corner k's opposite edge is (k+1, k+2)); -1 on a
// boundary or a non-manifold edge.
RowMatrixX3i FaceNeighbours(const RowMatrixX3i& faces) {
  struct HalfEdge {
    std::int64_t key;
    int face, corner;
  };
  const int m = static_cast<int>(faces.rows());
  std::vector<HalfEdge> edges;
  edges.reserve(3 * static_cast<std::size_t>(m));
  for (int f = 0; f < m; ++f)
    for (int k = 0; k < 3; ++k) {
      const std::int64_t a = faces(f, (k + 1) % 3), b = faces(f, (k + 2) % 3);
      edges.push_back({std::min(a, b) * (std::int64_t{1} << 32) + std::max(a, b), f, k});
    }
  std::sort(edges.begin(), edges.end(), [](const HalfEdge& x, const HalfEdge& y) { return x.key < y.key; });
  RowMatrixX3i neighbours = RowMatrixX3i::Constant(m, 3, -1);
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    if (j - i == 2) {
      neighbours(edges[i].face, edges[i].corner) = edges[i + 1].face;
      neighbours(edges[i + 1].face, edges[i + 1].corner) = edges[i].face;
    }
    i = j;
  }
  return neighbours;
}

// The edge-connected components of `faces` (a subset of the mesh) whose faces share a key.
std::vector<std::vector<int>> Components(const std::vector<int>& faces, const std::vector<int>& key,
                                         const RowMatrixX3i& neighbours, std::vector<int>* scratch) {
  std::vector<int>& mark = *scratch;  // per mesh face: -2 = not in the set, -1 = unvisited
  for (int f : faces) mark[f] = -1;
  std::vector<std::vector<int>> components;
  for (int seed : faces) {
    if (mark[seed] != -1) continue;
    std::vector<int> component = {seed};
    mark[seed] = static_cast<int>(components.size());
    for (std::size_t i = 0; i < component.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        const int g = neighbours(component[i], k);
        if (g >= 0 && mark[g] == -1 && key[g] == key[component[i]]) {
          mark[g] = mark[seed];
          component.push_back(g);
        }
      }
    components.push_back(std::move(component));
  }
  for (int f : faces) mark[f] = -2;
  return components;
}


class Flattener {
 public:
  Flattener(const Mesh& mesh, const RowMatrixX3i& neighbours, const UvAtlasOptions& options)
      : mesh_(mesh), neighbours_(neighbours), options_(options),
        vertex_slot_(mesh.num_vertices(), -1), in_chart_(mesh.num_faces(), -2) {}

  // Flattens `faces` into charts (cutting as needed) appended to `out`.
  void Flatten(std::vector<int> faces, std::vector<Chart>* out) {
    std::vector<std::vector<int>> queue = {std::move(faces)};
    while (!queue.empty()) {
      std::vector<int> part = std::move(queue.back());
      queue.pop_back();
      Chart chart;
      chart.faces = part;
      if (part.size() == 1 || TryFlatten(&chart)) {
        if (part.size() == 1) FlattenSingle(&chart);
        out->push_back(std::move(chart));
        continue;
      }
      for (std::vector<int>& half : Bisect(part)) queue.push_back(std::move(half));
    }
  }

 private:
  Eigen::Vector3d V(int v) const { return mesh_.vertices.row(v).transpose(); }

  void Index(Chart* chart) {
    chart->vertices.clear();
    chart->local.clear();
    for (int f : chart->faces)
      for (int k = 0; k < 3; ++k) {
        const int v = mesh_.faces(f, k);
        if (vertex_slot_[v] < 0) {
          vertex_slot_[v] = static_cast<int>(chart->vertices.size());
          chart->vertices.push_back(v);
        }
        chart->local.push_back(vertex_slot_[v]);
      }
    for (int v : chart->vertices) vertex_slot_[v] = -1;
  }

  void FlattenSingle(Chart* chart) {
    Index(chart);
    const int f = chart->faces[0];
    const Eigen::Vector3d a = V(mesh_.faces(f, 0)), b = V(mesh_.faces(f, 1)), c = V(mesh_.faces(f, 2));
    const Eigen::Vector3d e1 = b - a, e2 = c - a;
    const double l1 = std::max(e1.norm(), 1e-12);
    const Eigen::Vector3d x = e1 / l1;
    const double cx = e2.dot(x), cy = std::max((e2 - cx * x).norm(), 1e-12);
    chart->uv = {Eigen::Vector2d(0, 0), Eigen::Vector2d(l1, 0), Eigen::Vector2d(cx, cy)};
  }

  // LSCM with two pinned vertices; false when the chart is not a disc, flips, overlaps itself or
  // stretches too much.
  bool TryFlatten(Chart* chart) {
    Index(chart);
    const int n = static_cast<int>(chart->vertices.size());
    const int m = static_cast<int>(chart->faces.size());
    // Topology: a disc has Euler characteristic 1 and a boundary.
    int boundary_edges = 0, interior_edges = 0;
    for (int f : chart->faces) in_chart_[f] = 1;
    for (int f : chart->faces)
      for (int k = 0; k < 3; ++k) {
        const int g = neighbours_(f, k);
        if (g >= 0 && in_chart_[g] == 1) ++interior_edges;
        else ++boundary_edges;
      }
    const int edges = boundary_edges + interior_edges / 2;
    if (boundary_edges == 0 || n - edges + m != 1) {
      for (int f : chart->faces) in_chart_[f] = -2;
      return false;
    }
    // Pins: two far-apart boundary vertices.
    std::vector<char> on_boundary(n, 0);
    boundary_.clear();
    for (int i = 0; i < m; ++i) {
      const int f = chart->faces[i];
      for (int k = 0; k < 3; ++k) {
        const int g = neighbours_(f, k);
        if (g < 0 || in_chart_[g] != 1) {
          on_boundary[chart->local[3 * i + (k + 1) % 3]] = 1;
          on_boundary[chart->local[3 * i + (k + 2) % 3]] = 1;
          boundary_.emplace_back(chart->local[3 * i + (k + 1) % 3], chart->local[3 * i + (k + 2) % 3]);
        }
      }
    }
    for (int f : chart->faces) in_chart_[f] = -2;
    auto farthest = [&](int from) {
      int best = from;
      double best_d = -1;
      for (int i = 0; i < n; ++i)
        if (on_boundary[i]) {
          const double d = (V(chart->vertices[i]) - V(chart->vertices[from])).squaredNorm();
          if (d > best_d) best_d = d, best = i;
        }
      return best;
    };
    const int first = static_cast<int>(std::find(on_boundary.begin(), on_boundary.end(), 1) - on_boundary.begin());
    const int pin0 = farthest(first), pin1 = farthest(pin0);
    if (pin0 == pin1) return false;
    const double pin_distance = (V(chart->vertices[pin0]) - V(chart->vertices[pin1])).norm();
    // Unknowns: u and v of the free vertices.
    std::vector<int> column(n, -1);
    int free = 0;
    for (int i = 0; i < n; ++i)
      if (i != pin0 && i != pin1) column[i] = free++;
    auto pinned = [&](int i) { return i == pin0 ? Eigen::Vector2d(0, 0) : Eigen::Vector2d(pin_distance, 0); };
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(12 * static_cast<std::size_t>(m));
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * m);
    for (int i = 0; i < m; ++i) {
      const int f = chart->faces[i];
      const Eigen::Vector3d p0 = V(mesh_.faces(f, 0)), p1 = V(mesh_.faces(f, 1)), p2 = V(mesh_.faces(f, 2));
      const Eigen::Vector3d e1 = p1 - p0, e2 = p2 - p0;
      const double area = 0.5 * e1.cross(e2).norm();
      if (!(area > 1e-16)) continue;
      const double l1 = e1.norm();
      const Eigen::Vector3d x = e1 / l1;
      const double cx = e2.dot(x), cy = (e2 - cx * x).norm();
      const Eigen::Vector2d z[3] = {Eigen::Vector2d(0, 0), Eigen::Vector2d(l1, 0), Eigen::Vector2d(cx, cy)};
      const double scale = 1.0 / std::sqrt(area);
      for (int j = 0; j < 3; ++j) {
        // W_j = z_{j+2} - z_{j+1}: sum_j W_j U_j is proportional to dU/dconj(z) (zero when conformal).
        const Eigen::Vector2d w = (z[(j + 2) % 3] - z[(j + 1) % 3]) * scale;
        const int vertex = chart->local[3 * i + j];
        if (column[vertex] < 0) {
          const Eigen::Vector2d U = pinned(vertex);
          rhs[2 * i] -= w.x() * U.x() - w.y() * U.y();
          rhs[2 * i + 1] -= w.y() * U.x() + w.x() * U.y();
        } else {
          const int cu = column[vertex], cv = free + column[vertex];
          triplets.emplace_back(2 * i, cu, w.x());
          triplets.emplace_back(2 * i, cv, -w.y());
          triplets.emplace_back(2 * i + 1, cu, w.y());
          triplets.emplace_back(2 * i + 1, cv, w.x());
        }
      }
    }
    Eigen::SparseMatrix<double> A(2 * m, 2 * free);
    A.setFromTriplets(triplets.begin(), triplets.end());
    Eigen::SparseMatrix<double> normal = A.transpose() * A;
    double trace = 0;
    for (int k = 0; k < normal.outerSize(); ++k) trace += normal.coeff(k, k);
    Eigen::SparseMatrix<double> identity(2 * free, 2 * free);
    identity.setIdentity();
    normal += identity * (1e-10 * trace / std::max(1, 2 * free));
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
    if (solver.info() != Eigen::Success) return false;
    const Eigen::VectorXd solution = solver.solve(A.transpose() * rhs);
    if (solver.info() != Eigen::Success || !solution.allFinite()) return false;
    chart->uv.assign(n, Eigen::Vector2d::Zero());
    for (int i = 0; i < n; ++i)
      chart->uv[i] = column[i] < 0 ? pinned(i) : Eigen::Vector2d(solution[column[i]], solution[free + column[i]]);
    // Normalise: UV area = surface area.
    double area_3d = 0, area_uv = 0;
    for (int i = 0; i < m; ++i) {
      const int f = chart->faces[i];
      area_3d += 0.5 * (V(mesh_.faces(f, 1)) - V(mesh_.faces(f, 0))).cross(V(mesh_.faces(f, 2)) - V(mesh_.faces(f, 0))).norm();
      area_uv += SignedArea(*chart, i);
    }
    if (!(area_uv > 0) || !(area_3d > 0)) return false;
    const double s = std::sqrt(area_3d / area_uv);
    for (Eigen::Vector2d& p : chart->uv) p *= s;
    // Flips, stretch, overlaps.
    double stretch_sum = 0;
    for (int i = 0; i < m; ++i) {
      const int f = chart->faces[i];
      const double a3 = FaceArea(f);
      if (!(a3 > 1e-14)) continue;
      if (!(SignedArea(*chart, i) > 1e-6 * a3)) return false;
      stretch_sum += a3 * SquaredStretch(*chart, i);
    }
    if (std::sqrt(stretch_sum / area_3d) > options_.max_chart_stretch) return false;
    if (m >= 256 && BoxFill(*chart, area_3d) < options_.min_chart_fill) return false;
    return !OverlapsItself(*chart, on_boundary);
  }

  // The chart's UV area (`area`, equal to its surface area) over the area of its bounding box in
  // its principal axes.
  static double BoxFill(const Chart& chart, double area) {
    Chart oriented = chart;
    OrientChart(&oriented);
    return area / std::max(oriented.width * oriented.height, 1e-30);
  }

  double FaceArea(int f) const {
    return 0.5 * (V(mesh_.faces(f, 1)) - V(mesh_.faces(f, 0))).cross(V(mesh_.faces(f, 2)) - V(mesh_.faces(f, 0))).norm();
  }

  static double SignedArea(const Chart& chart, int i) {
    const Eigen::Vector2d a = chart.uv[chart.local[3 * i]], b = chart.uv[chart.local[3 * i + 1]],
                          c = chart.uv[chart.local[3 * i + 2]];
    return 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
  }

 public:
  // Sander et al.'s L2 stretch squared of chart face i (uv in metres).
  double SquaredStretch(const Chart& chart, int i) const {
    const int f = chart.faces[i];
    const Eigen::Vector2d p1 = chart.uv[chart.local[3 * i]], p2 = chart.uv[chart.local[3 * i + 1]],
                          p3 = chart.uv[chart.local[3 * i + 2]];
    const double area2 = (p2.x() - p1.x()) * (p3.y() - p1.y()) - (p3.x() - p1.x()) * (p2.y() - p1.y());
    if (!(area2 > 0)) return INFINITY;
    const Eigen::Vector3d q1 = V(mesh_.faces(f, 0)), q2 = V(mesh_.faces(f, 1)), q3 = V(mesh_.faces(f, 2));
    const Eigen::Vector3d Ss = (q1 * (p2.y() - p3.y()) + q2 * (p3.y() - p1.y()) + q3 * (p1.y() - p2.y())) / area2;
    const Eigen::Vector3d St = (q1 * (p3.x() - p2.x()) + q2 * (p1.x() - p3.x()) + q3 * (p2.x() - p1.x())) / area2;
    return 0.5 * (Ss.squaredNorm() + St.squaredNorm());
  }

 private:
  // True when the flattened chart is not embedded. Its triangles are all counter-clockwise, so
  // it is an immersion where every interior vertex's angles sum to 2 pi; an immersed disc whose
  // boundary does not cross itself is embedded. Checked exactly: the angle sums, and every pair
  // of boundary edges without a common vertex (bucketed on a grid) for an intersection.
  bool OverlapsItself(const Chart& chart, const std::vector<char>& on_boundary) const {
    const int n = static_cast<int>(chart.uv.size());
    std::vector<double> angle(n, 0.0);
    for (std::size_t i = 0; i < chart.faces.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector2d a = chart.uv[chart.local[3 * i + k]], b = chart.uv[chart.local[3 * i + (k + 1) % 3]],
                              c = chart.uv[chart.local[3 * i + (k + 2) % 3]];
        const Eigen::Vector2d u = b - a, v = c - a;
        angle[chart.local[3 * i + k]] += std::atan2(u.x() * v.y() - u.y() * v.x(), u.dot(v));
      }
    for (int i = 0; i < n; ++i)
      if (!on_boundary[i] && std::abs(angle[i] - 2.0 * M_PI) > 0.1) return true;
    const std::size_t edges = boundary_.size();
    Eigen::Vector2d lo(1e30, 1e30), hi(-1e30, -1e30);
    double length = 0;
    for (const auto& [a, b] : boundary_) {
      lo = lo.cwiseMin(chart.uv[a]).cwiseMin(chart.uv[b]);
      hi = hi.cwiseMax(chart.uv[a]).cwiseMax(chart.uv[b]);
      length += (chart.uv[a] - chart.uv[b]).norm();
    }
    const double cell = std::max(length / std::max<std::size_t>(edges, 1), 1e-12);
    const int w = std::min(4096, static_cast<int>((hi.x() - lo.x()) / cell) + 1);
    const int h = std::min(4096, static_cast<int>((hi.y() - lo.y()) / cell) + 1);
    const double sx = w / std::max(hi.x() - lo.x(), 1e-30), sy = h / std::max(hi.y() - lo.y(), 1e-30);
    std::vector<std::vector<int>> grid(static_cast<std::size_t>(w) * h);
    auto orient = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
      const double d = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
      return d > 0 ? 1 : d < 0 ? -1 : 0;
    };
    for (std::size_t e = 0; e < edges; ++e) {
      const auto [a, b] = boundary_[e];
      const Eigen::Vector2d p = chart.uv[a], q = chart.uv[b];
      const int x0 = std::clamp(static_cast<int>((std::min(p.x(), q.x()) - lo.x()) * sx), 0, w - 1);
      const int x1 = std::clamp(static_cast<int>((std::max(p.x(), q.x()) - lo.x()) * sx), 0, w - 1);
      const int y0 = std::clamp(static_cast<int>((std::min(p.y(), q.y()) - lo.y()) * sy), 0, h - 1);
      const int y1 = std::clamp(static_cast<int>((std::max(p.y(), q.y()) - lo.y()) * sy), 0, h - 1);
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
          std::vector<int>& bucket = grid[static_cast<std::size_t>(y) * w + x];
          for (int f : bucket) {
            const auto [c, d] = boundary_[f];
            if (c == a || c == b || d == a || d == b) continue;
            const Eigen::Vector2d r = chart.uv[c], t = chart.uv[d];
            if (orient(p, q, r) * orient(p, q, t) <= 0 && orient(r, t, p) * orient(r, t, q) <= 0) return true;
          }
          bucket.push_back(static_cast<int>(e));
        }
    }
    return false;
  }

 public:
  // Calls hit(x, y) for every sample (x, y) (integer grid) strictly inside triangle p; stops and
  // returns true when hit returns true.
  template <typename Hit>
  static bool RasteriseTriangle(const Eigen::Vector2d p[3], int w, int h, const Hit& hit) {
    const double area2 = (p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x();
    if (!(area2 > 0)) return false;
    const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({p[0].x(), p[1].x(), p[2].x()}))));
    const int x1 = std::min(w - 1, static_cast<int>(std::floor(std::max({p[0].x(), p[1].x(), p[2].x()}))));
    const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({p[0].y(), p[1].y(), p[2].y()}))));
    const int y1 = std::min(h - 1, static_cast<int>(std::floor(std::max({p[0].y(), p[1].y(), p[2].y()}))));
    const double eps = 1e-9 * area2;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d q(x, y);
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
          const Eigen::Vector2d a = p[(k + 1) % 3], b = p[(k + 2) % 3];
          inside = (b - a).x() * (q - a).y() - (b - a).y() * (q - a).x() > eps;
        }
        if (inside && hit(x, y)) return true;
      }
    return false;
  }

 private:
  // Two halves across the area-weighted principal axis of the faces' centroids, each split into
  // connected components.
  std::vector<std::vector<int>> Bisect(const std::vector<int>& faces) {
    std::vector<Eigen::Vector3d> centre(faces.size());
    std::vector<double> weight(faces.size());
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    double total = 0;
    for (std::size_t i = 0; i < faces.size(); ++i) {
      const int f = faces[i];
      centre[i] = (V(mesh_.faces(f, 0)) + V(mesh_.faces(f, 1)) + V(mesh_.faces(f, 2))) / 3.0;
      weight[i] = FaceArea(f) + 1e-12;
      mean += weight[i] * centre[i];
      total += weight[i];
    }
    mean /= total;
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < faces.size(); ++i)
      covariance += weight[i] * (centre[i] - mean) * (centre[i] - mean).transpose();
    const Eigen::Vector3d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvectors().col(2);
    std::vector<std::size_t> order(faces.size());
    std::iota(order.begin(), order.end(), 0);
    std::vector<double> t(faces.size());
    for (std::size_t i = 0; i < faces.size(); ++i) t[i] = axis.dot(centre[i]);
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return t[a] < t[b]; });
    std::vector<int> side(mesh_.num_faces(), 0);
    double accumulated = 0;
    for (std::size_t r = 0; r < order.size(); ++r) {
      const std::size_t i = order[r];
      // At least one face on each side.
      const bool upper = r > 0 && (accumulated >= 0.5 * total || r + 1 == order.size());
      side[faces[i]] = upper ? 1 : 0;
      accumulated += weight[i];
    }
    return Components(faces, side, neighbours_, &in_chart_);
  }

  const Mesh& mesh_;
  const RowMatrixX3i& neighbours_;
  const UvAtlasOptions& options_;
  std::vector<int> vertex_slot_;
  std::vector<int> in_chart_;
  std::vector<std::pair<int, int>> boundary_;  // the chart's boundary edges (chart vertices)
};

}  // namespace

void UvAtlasOptions::Check() const {
  RequireOption(size_px >= 64 && size_px <= 16384, "UvAtlasOptions.size_px", size_px, "in [64, 16384]");
  RequireOption(padding_px >= 0 && padding_px <= 64, "UvAtlasOptions.padding_px", padding_px, "in [0, 64]");
  RequireOption(max_chart_stretch >= 1.0, "UvAtlasOptions.max_chart_stretch", max_chart_stretch, ">= 1");
  RequireOption(min_chart_faces >= 0, "UvAtlasOptions.min_chart_faces", min_chart_faces, ">= 0");
  RequireOption(min_chart_fill >= 0.0 && min_chart_fill < 1.0, "UvAtlasOptions.min_chart_fill", min_chart_fill, "in [0, 1)");
  RequireOption(smoothing_passes >= 0 && smoothing_passes <= 100, "UvAtlasOptions.smoothing_passes",
                smoothing_passes, "in [0, 100]");
}

UvAtlas BuildUvAtlas(const Mesh& mesh, const UvAtlasOptions& options) {
  options.Check();
  const int n = mesh.num_vertices(), m = mesh.num_faces();
  if (m == 0) throw InputError("mesh", "has no faces: no UV atlas");
  if (!mesh.vertices.allFinite()) throw InputError("mesh", "has non-finite vertices");
  if (mesh.faces.minCoeff() < 0 || mesh.faces.maxCoeff() >= n)
    throw InputError("mesh", "has a face index out of range (" + std::to_string(n) + " vertices)");
  const RowMatrixX3i neighbours = FaceNeighbours(mesh.faces);

  // Grouping: segment label and the normal's dominant axis, smoothed.
  std::vector<Eigen::Vector3d> normal(m);
  double total_area = 0;
  for (int f = 0; f < m; ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0)), b = mesh.vertices.row(mesh.faces(f, 1)),
                          c = mesh.vertices.row(mesh.faces(f, 2));
    normal[f] = (b - a).cross(c - a);
    total_area += 0.5 * normal[f].norm();
    if (normal[f].norm() > 0) normal[f].normalize();
  }
  if (!(total_area > 0)) throw InputError("mesh", "has zero surface area: no UV atlas");
  const bool labelled = mesh.has_face_labels();
  std::vector<int> axis(m);
  for (int f = 0; f < m; ++f) {
    int best = 0;
    for (int k = 1; k < 3; ++k)
      if (std::abs(normal[f][k]) > std::abs(normal[f][best])) best = k;
    axis[f] = 2 * best + (normal[f][best] < 0 ? 1 : 0);
  }
  auto axis_dot = [&](int f, int a) { return (a % 2 ? -1.0 : 1.0) * normal[f][a / 2]; };
  auto label = [&](int f) { return labelled ? mesh.face_labels[f] : 0; };
  for (int pass = 0; pass < options.smoothing_passes; ++pass) {
    std::vector<int> next = axis;
    for (int f = 0; f < m; ++f) {
      int votes[6] = {0, 0, 0, 0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const int g = neighbours(f, k);
        if (g >= 0 && label(g) == label(f)) ++votes[axis[g]];
      }
      const int best = static_cast<int>(std::max_element(votes, votes + 6) - votes);
      if (best != axis[f] && votes[best] >= 2 && axis_dot(f, best) > 0.2) next[f] = best;
    }
    axis.swap(next);
  }
  std::vector<int> key(m);
  std::map<int, int> label_index;
  for (int f = 0; f < m; ++f) {
    const int l = label_index.emplace(label(f), static_cast<int>(label_index.size())).first->second;
    key[f] = 6 * l + axis[f];
  }
  std::vector<int> all(m);
  std::iota(all.begin(), all.end(), 0);
  std::vector<int> scratch(m, -2);
  std::vector<std::vector<int>> groups = Components(all, key, neighbours, &scratch);
  // Small pieces join the neighbouring group they share most edges with.
  if (options.min_chart_faces > 0) {
    std::vector<int> group_of(m);
    for (std::size_t g = 0; g < groups.size(); ++g)
      for (int f : groups[g]) group_of[f] = static_cast<int>(g);
    std::vector<int> order(groups.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return groups[a].size() < groups[b].size(); });
    for (int g : order) {
      if (groups[g].empty() || static_cast<int>(groups[g].size()) >= options.min_chart_faces) continue;
      std::map<int, int> shared;
      for (int f : groups[g])
        for (int k = 0; k < 3; ++k) {
          const int h = neighbours(f, k);
          if (h >= 0 && group_of[h] != g) ++shared[group_of[h]];
        }
      if (shared.empty()) continue;
      const int target = std::max_element(shared.begin(), shared.end(), [](const auto& a, const auto& b) {
                           return a.second < b.second;
                         })->first;
      for (int f : groups[g]) group_of[f] = target;
      groups[target].insert(groups[target].end(), groups[g].begin(), groups[g].end());
      groups[g].clear();
    }
  }

  // Flatten, cutting as needed.
  Flattener flattener(mesh, neighbours, options);
  std::vector<Chart> charts;
  for (std::vector<int>& group : groups)
    if (!group.empty()) flattener.Flatten(std::move(group), &charts);
  for (Chart& chart : charts) OrientChart(&chart);

  // Pack: the largest density that fits.
  std::vector<int> order(charts.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return charts[a].height != charts[b].height ? charts[a].height > charts[b].height : a < b;
  });
  const int size = options.size_px, padding = options.padding_px;
  double hi = std::sqrt(size * static_cast<double>(size) / total_area), lo = 0;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (Pack(&charts, order, mid, size, padding)) lo = mid;
    else hi = mid;
  }
  if (!(lo > 0) || !Pack(&charts, order, lo, size, padding))
    throw InputError("mesh", std::to_string(charts.size()) + " UV charts do not fit a " + std::to_string(size) +
                                 " px atlas with " + std::to_string(padding) + " px padding");

  UvAtlas atlas;
  atlas.size_px = size;
  atlas.stats.charts = static_cast<int>(charts.size());
  std::size_t corners = 0;
  for (const Chart& chart : charts) corners += chart.vertices.size();
  atlas.uvs.resize(static_cast<Eigen::Index>(corners), 2);
  atlas.face_uvs.resize(m, 3);
  int next = 0;
  double stretch_sum = 0, area_sum = 0, stretch_max = 0;
  for (const Chart& chart : charts) {
    for (std::size_t i = 0; i < chart.vertices.size(); ++i) {
      // Position in the chart's box (texels), turned by +90 degrees when packed so.
      const Eigen::Vector2d p = (chart.uv[i] - Eigen::Vector2d(chart.min_u, chart.min_v)) * lo;
      const Eigen::Vector2d q = chart.turned ? Eigen::Vector2d(chart.height * lo - p.y(), p.x()) : p;
      const double x = chart.x + padding + 0.5 + q.x();
      const double y = chart.y + padding + 0.5 + q.y();
      atlas.uvs.row(next + static_cast<int>(i)) = Eigen::RowVector2d(x / size, y / size);
    }
    for (std::size_t i = 0; i < chart.faces.size(); ++i) {
      for (int k = 0; k < 3; ++k) atlas.face_uvs(chart.faces[i], k) = next + chart.local[3 * i + k];
      const int f = chart.faces[i];
      const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0)), b = mesh.vertices.row(mesh.faces(f, 1)),
                            c = mesh.vertices.row(mesh.faces(f, 2));
      const double a3 = 0.5 * (b - a).cross(c - a).norm();
      if (!(a3 > 1e-14)) continue;
      const double s2 = flattener.SquaredStretch(chart, static_cast<int>(i));
      stretch_sum += a3 * s2;
      area_sum += a3;
      stretch_max = std::max(stretch_max, std::sqrt(s2));
    }
    next += static_cast<int>(chart.vertices.size());
  }
  // Charts were scaled to UV area = surface area each, so this is Sander's normalised L2 norm.
  atlas.stats.stretch_mean = area_sum > 0 ? std::sqrt(stretch_sum / area_sum) : 1.0;
  atlas.stats.stretch_max = stretch_max;
  // Texel use: texel centres inside a UV triangle.
  std::vector<std::uint8_t> used(static_cast<std::size_t>(size) * size, 0);
  std::size_t covered = 0;
  for (int f = 0; f < m; ++f) {
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) p[k] = atlas.uvs.row(atlas.face_uvs(f, k)).transpose() * size - Eigen::Vector2d(0.5, 0.5);
    Flattener::RasteriseTriangle(p, size, size, [&](int x, int y) {
      std::uint8_t& u = used[static_cast<std::size_t>(y) * size + x];
      covered += u == 0;
      u = 1;
      return false;
    });
  }
  atlas.stats.texel_use = static_cast<double>(covered) / (static_cast<double>(size) * size);
  return atlas;
}

Mesh WithAtlasUvs(const Mesh& mesh, const UvAtlas& atlas) {
  if (atlas.face_uvs.rows() != mesh.faces.rows())
    throw InputError("UV atlas", "has " + std::to_string(atlas.face_uvs.rows()) + " faces, the mesh " +
                                     std::to_string(mesh.faces.rows()));
  Mesh out = mesh;
  out.uvs = atlas.uvs;
  out.face_uvs = atlas.face_uvs;
  out.texture_path.clear();
  return out;
}

}  // namespace confluent
