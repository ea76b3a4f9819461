#include "deform/confluent_motion.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <queue>
#include <stdexcept>

#include "core/error.h"
#include "deform/cholmod_solver.h"
#include "deform/helper_thread.h"
#include "deform/motion_kernels.h"

namespace confluent {

void ConfluentMotionOptions::Check() const {
  laplacian.Check();
  if (!(singular_w >= 0.0 && singular_w < 1.0) || max_segment_fields < 1 || !(segment_rigid_tolerance_rad >= 0.0) ||
      !(position_weight >= 0.0) || threads < 1)
    std::abort();
}

namespace {

using deform_internal::Aligned32;
using deform_internal::AssembleFaces;
using deform_internal::FaceAssembly;
using deform_internal::kFaceBlock;
using deform_internal::MixFields;
using RowMatrixX4d = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;
using Weights = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

Eigen::Vector4d ToVector(const Eigen::Quaterniond& q) { return Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()); }

// Rotation that best maps triangle `from` onto triangle `to` (Kabsch: the rotation part of the
// polar decomposition of the cross-covariance of centred corners plus the scaled normal).
// Returns false (and the identity) for a degenerate triangle.
bool TriangleRotation(const Eigen::Matrix3d& from, const Eigen::Matrix3d& to, Eigen::Quaterniond* rotation) {
  // Rows are corners.
  const Eigen::RowVector3d from_centre = from.colwise().mean(), to_centre = to.colwise().mean();
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (int k = 0; k < 3; ++k) h += (from.row(k) - from_centre).transpose() * (to.row(k) - to_centre);
  const Eigen::Vector3d from_normal = (from.row(1) - from.row(0)).cross(from.row(2) - from.row(0)).transpose();
  const Eigen::Vector3d to_normal = (to.row(1) - to.row(0)).cross(to.row(2) - to.row(0)).transpose();
  const double from_area = from_normal.norm(), to_area = to_normal.norm();
  const double scale = std::max((from.row(1) - from.row(0)).squaredNorm(), (from.row(2) - from.row(0)).squaredNorm());
  if (!(from_area > 1e-12 * scale) || !(to_area > 1e-12 * scale) || !h.allFinite()) {
    *rotation = Eigen::Quaterniond::Identity();
    return false;
  }
  // Normals scaled to edge-length units.
  h += (from_normal / std::sqrt(from_area)) * (to_normal / std::sqrt(to_area)).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  const Eigen::Matrix3d r = svd.matrixV() * d * svd.matrixU().transpose();
  *rotation = Eigen::Quaterniond(r);
  rotation->normalize();
  return true;
}

// Runs fn(begin, end, part) on the two halves of [0, count), part 1 on `helper`, when
// `parallel`; else fn(0, count, 0).
template <typename Function>
void ForHalves(HelperThread* helper, bool parallel, int count, const Function& fn) {
  if (!parallel) {
    fn(0, count, 0);
    return;
  }
  helper->Run([&fn, count](int part) { fn(part == 0 ? 0 : count / 2, part == 0 ? count / 2 : count, part); });
}

// Below this many vertices or faces, a per-frame loop runs on one thread.
constexpr int kMinParallelItems = 8192;

Eigen::Matrix3d Corners(const RowMatrixX3d& vertices, const RowMatrixX3i& faces, int f) {
  Eigen::Matrix3d corners;
  for (int k = 0; k < 3; ++k) corners.row(k) = vertices.row(faces(f, k));
  return corners;
}

// The Laplace equation with Dirichlet values at `constrained` vertices, reduced to the free ones:
// L_ff x_f = -L_fc x_c. Factor() fills everything; solve with factor and minus_l_fc.
struct DirichletSystem {
  std::vector<int> constrained, free_vertices;  // scan vertex ids
  Eigen::SparseMatrix<double> minus_l_fc;       // n_f x n_c
  SparseCholesky factor;                        // of L_ff; empty when every vertex is constrained

  // Returns false (with factor.message()) when L_ff cannot be factored.
  bool Factor(const Eigen::SparseMatrix<double>& laplacian, const std::vector<int>& constrained_vertices, int threads,
              bool single_precision) {
    const int n = static_cast<int>(laplacian.rows());
    constrained = constrained_vertices;
    free_vertices.clear();
    std::vector<int> constrained_index(n, -1), free_index(n, -1);
    for (std::size_t i = 0; i < constrained.size(); ++i) constrained_index[constrained[i]] = static_cast<int>(i);
    for (int v = 0; v < n; ++v)
      if (constrained_index[v] < 0) {
        free_index[v] = static_cast<int>(free_vertices.size());
        free_vertices.push_back(v);
      }
    const int num_free = static_cast<int>(free_vertices.size());
    std::vector<Eigen::Triplet<double>> ff, fc;
    for (int col = 0; col < laplacian.outerSize(); ++col)
      for (Eigen::SparseMatrix<double>::InnerIterator it(laplacian, col); it; ++it) {
        const int row = static_cast<int>(it.row());
        if (free_index[row] < 0) continue;
        if (free_index[col] >= 0)
          ff.emplace_back(free_index[row], free_index[col], it.value());
        else
          fc.emplace_back(free_index[row], constrained_index[col], -it.value());
      }
    Eigen::SparseMatrix<double> l_ff(num_free, num_free);
    l_ff.setFromTriplets(ff.begin(), ff.end());
    minus_l_fc.resize(num_free, static_cast<int>(constrained.size()));
    minus_l_fc.setFromTriplets(fc.begin(), fc.end());
    factor = SparseCholesky();
    if (num_free > 0 && factor.Factor(l_ff) != CholeskyStatus::kOk) return false;
    factor.set_threads(threads);
    factor.set_single_precision(single_precision);
    return true;
  }

  // Fills `field` (n x k) with the harmonic interpolation of `values` (n_c x k) given at the
  // constrained vertices; vertex v goes to row row_of[v] (row v when row_of is null).
  template <typename Field>
  void Solve(const Eigen::MatrixXd& values, Field* field, const std::vector<int>* row_of = nullptr) const {
    auto row = [&](int v) { return row_of != nullptr ? (*row_of)[v] : v; };
    for (std::size_t i = 0; i < constrained.size(); ++i) field->row(row(constrained[i])) = values.row(i);
    if (free_vertices.empty()) return;
    const Eigen::MatrixXd at_free = factor.Solve(Eigen::MatrixXd(minus_l_fc * values));
    for (std::size_t i = 0; i < free_vertices.size(); ++i) field->row(row(free_vertices[i])) = at_free.row(i);
  }
};

// Spherical linear interpolation from a (t = 0) to b (t = 1) along the great circle through
// them as given (no sign flip: with continuous signs the long way round is the intended one).
Eigen::Vector4d Slerp(const Eigen::Vector4d& a, const Eigen::Vector4d& b, double t) {
  const double cosine = std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0);
  const double angle = std::acos(cosine);
  if (std::sin(angle) < 1e-6) return ((1.0 - t) * a + t * b).normalized();  // (anti)parallel
  return (std::sin((1.0 - t) * angle) * a + std::sin(t * angle) * b) / std::sin(angle);
}

// One scan vertex on a SLERP path: its quaternion is Slerp(q[from_pair], q[to_pair], t).
struct PathVertex {
  int vertex = -1;
  int from_pair = -1;  // the well-conditioned pair the path starts at
  int to_pair = -1;    // the near-180-degree pair it ends at
  double t = 0.0;
};

}  // namespace

struct ConfluentMotion::Impl {
  ConfluentMotionOptions options;
  ConfluentMotionSetupSummary setup;
  // Scan.
  RowMatrixX3d scan_vertices;
  RowMatrixX3i scan_faces;
  Weights weights;                      // half cotangents per face corner
  std::vector<int> component_of_vertex, component_of_face;
  int num_components = 0;
  std::vector<int> unreferenced;        // vertices used by no face
  // Template.
  RowMatrixX3d template_reference;
  RowMatrixX3i template_faces;
  // Pairs.
  std::vector<CorrespondencePair> pairs;
  std::vector<Eigen::Vector3d> scan_centroid_ref, template_centroid_ref;
  std::vector<int> align_order, align_parent;  // spanning tree over pairs for sign alignment
  // Harmonic system.
  Eigen::SparseMatrix<double> average;     // n_c x m: Dirichlet value of each constrained vertex
  DirichletSystem harmonic;
  // SLERP paths (options.slerp_paths): the Laplacian is kept to refactor with the path vertices
  // constrained; `path_pairs` is the set of near-180-degree pairs the paths were built for.
  Eigen::SparseMatrix<double> laplacian;
  std::vector<std::vector<std::pair<int, double>>> edges_of_vertex;  // neighbour, edge length
  std::vector<int> path_pairs;
  std::vector<PathVertex> path_vertices;
  std::vector<std::vector<int>> path_vertices_at;  // per extra constrained vertex: path_vertices ids
  DirichletSystem path_harmonic;
  // Segment weight fields (n x s, rows in the Poisson factor's ordering), when all pairs are labelled.
  std::vector<int> segment_of_pair;
  int num_segments = 0;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> segment_fields;
  // Poisson system.
  SparseCholesky poisson;
  double position_weight = 0.0;  // absolute weight of the soft positional constraints
  // The per-frame arrays over vertices are in the Poisson factor's ordering: vertex v is row
  // row_of_vertex[v] (vertex_of_row is the inverse), so the right-hand side is assembled where
  // the triangular solves read it.
  std::vector<int> row_of_vertex, vertex_of_row;
  // Faces are visited in slots sorted by their first row, so that the rows they touch are near
  // each other in memory.
  std::vector<int> face_of_slot;
  std::vector<int> face_rows;        // per slot, its face's corners' rows
  std::vector<double> flux_edges;    // per block of slots: g0, g1 of FaceAssembly
  HelperThread helper;               // second thread of the per-frame loops
  // Frame state.
  int frame = 0;
  bool has_previous = false;
  RowMatrixX3d previous_template;
  RowMatrixX4d previous_face_rotations;  // from the scan's reference pose
  std::vector<Eigen::Vector4d> previous_constraints;  // aligned, relative to the active reference
  std::vector<Eigen::Vector4d> previous_full;  // aligned, relative to the reference pose
  int previous_reference = -2;             // active reference of the previous frame
  // Per-frame buffers, kept to avoid allocations: vertex quaternions (by row), the right-hand
  // side (n x 4, 32-byte aligned, for the solve in place) and the helper thread's part of it,
  // and the face rotations being computed.
  RowMatrixX4d vertex_q;
  std::vector<double> rhs_storage, partial_storage;
  RowMatrixX4d next_face_rotations;
  // Intermediate reference (report section 4.3).
  int intermediate_frame = -1;
  RowMatrixX3d intermediate_template;
  RowMatrixX4d intermediate_face_rotations;

  // Rebuilds the SLERP paths and their harmonic system when the set of near-180-degree pairs
  // (w of `q` below options.singular_w) differs from the one they were built for. Returns the
  // number of path-constrained vertices (0 when no path could be built; `warnings` says why).
  int UpdateSlerpPaths(const std::vector<Eigen::Vector4d>& q, std::vector<std::string>* warnings) {
    const int m = static_cast<int>(pairs.size());
    std::vector<int> singular;
    for (int k = 0; k < m; ++k)
      if (q[k](0) < options.singular_w) singular.push_back(k);
    if (singular == path_pairs) return static_cast<int>(path_vertices_at.size());
    path_pairs = singular;
    path_vertices.clear();
    path_vertices_at.clear();
    const int n = static_cast<int>(scan_vertices.rows());
    if (edges_of_vertex.empty()) {
      edges_of_vertex.resize(n);
      for (int f = 0; f < scan_faces.rows(); ++f)
        for (int k = 0; k < 3; ++k) {
          const int a = scan_faces(f, k), b = scan_faces(f, (k + 1) % 3);
          const double length = (scan_vertices.row(a) - scan_vertices.row(b)).norm();
          edges_of_vertex[a].emplace_back(b, length);
          edges_of_vertex[b].emplace_back(a, length);
        }
    }
    // Multi-source Dijkstra from the well-conditioned pairs' scan triangles.
    std::vector<double> distance(n, std::numeric_limits<double>::infinity());
    std::vector<int> previous(n, -1), source_pair(n, -1);
    using Entry = std::pair<double, int>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
    std::vector<char> is_singular(m, 0);
    for (int k : singular) is_singular[k] = 1;
    for (int k = 0; k < m; ++k)
      if (!is_singular[k])
        for (int c = 0; c < 3; ++c) {
          const int v = scan_faces(pairs[k].scan_triangle, c);
          if (distance[v] == 0.0) continue;
          distance[v] = 0.0;
          source_pair[v] = k;
          queue.emplace(0.0, v);
        }
    if (queue.empty()) {
      warnings->push_back("every constraint rotation is near 180 degrees: no SLERP path can start anywhere");
      return 0;
    }
    while (!queue.empty()) {
      const auto [d, v] = queue.top();
      queue.pop();
      if (d > distance[v]) continue;
      for (const auto& [w, length] : edges_of_vertex[v])
        if (d + length < distance[w]) {
          distance[w] = d + length;
          previous[w] = v;
          source_pair[w] = source_pair[v];
          queue.emplace(distance[w], w);
        }
    }
    // Each path: from the singular triangle's nearest corner back to a source.
    std::vector<char> constrained(n, 0);
    for (int v : harmonic.constrained) constrained[v] = 1;
    std::map<int, int> extra_index;  // scan vertex -> row among the extra constrained vertices
    std::vector<int> extra;
    for (int k : singular) {
      int start = scan_faces(pairs[k].scan_triangle, 0);
      for (int c = 1; c < 3; ++c)
        if (distance[scan_faces(pairs[k].scan_triangle, c)] < distance[start]) start = scan_faces(pairs[k].scan_triangle, c);
      if (!std::isfinite(distance[start]) || !(distance[start] > 0.0)) continue;
      for (int v = start; v >= 0 && distance[v] > 0.0; v = previous[v]) {
        if (constrained[v]) continue;
        const auto inserted = extra_index.emplace(v, static_cast<int>(extra.size()));
        if (inserted.second) {
          extra.push_back(v);
          path_vertices_at.emplace_back();
        }
        path_vertices_at[inserted.first->second].push_back(static_cast<int>(path_vertices.size()));
        path_vertices.push_back({v, source_pair[start], k, distance[v] / distance[start]});
      }
    }
    if (extra.empty()) return 0;
    std::vector<int> all = harmonic.constrained;
    all.insert(all.end(), extra.begin(), extra.end());
    if (!path_harmonic.Factor(laplacian, all, options.threads, options.single_precision_solves)) {
      warnings->push_back("the harmonic system with SLERP path constraints cannot be factored: " +
                          path_harmonic.factor.message());
      path_vertices.clear();
      path_vertices_at.clear();
      return 0;
    }
    return static_cast<int>(extra.size());
  }

  std::vector<Eigen::Quaterniond> ConstraintRotations(const RowMatrixX3d& from, const RowMatrixX3d& to,
                                                      std::vector<int>* degenerate) const {
    std::vector<Eigen::Quaterniond> result(pairs.size());
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const int t = pairs[k].template_triangle;
      if (!TriangleRotation(Corners(from, template_faces, t), Corners(to, template_faces, t), &result[k]) && degenerate)
        degenerate->push_back(static_cast<int>(k));
    }
    return result;
  }
};

ConfluentMotion::ConfluentMotion(const Mesh& scan, const Mesh& template_reference,
                                 const Correspondences& correspondences, const ConfluentMotionOptions& options,
                                 const std::string& scan_source, const std::string& correspondences_source)
    : impl_(std::make_unique<Impl>()) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  Impl& s = *impl_;
  s.options = options;
  if (scan.num_faces() == 0) throw InputError(scan_source, "the scan has no faces");
  if (template_reference.num_faces() == 0) throw InputError("template", "the template has no faces");
  if (!scan.vertices.allFinite()) throw InputError(scan_source, "the scan has non-finite vertex coordinates");
  if (!template_reference.vertices.allFinite())
    throw InputError("template", "the template has non-finite vertex coordinates");
  ValidateCorrespondences(correspondences, template_reference.num_faces(), scan.num_faces(), correspondences_source);
  s.scan_vertices = scan.vertices;
  s.scan_faces = scan.faces;
  s.template_reference = template_reference.vertices;
  s.template_faces = template_reference.faces;
  s.pairs = correspondences.pairs;
  const int n = scan.num_vertices(), m = static_cast<int>(s.pairs.size());
  s.setup.num_scan_vertices = n;
  s.setup.num_scan_faces = scan.num_faces();
  s.setup.num_pairs = m;

  // Degenerate template triangles cannot carry a rotation.
  for (int k = 0; k < m; ++k) {
    Eigen::Quaterniond q;
    const Eigen::Matrix3d corners = Corners(s.template_reference, s.template_faces, s.pairs[k].template_triangle);
    if (!TriangleRotation(corners, corners, &q))
      throw InputError(correspondences_source, "pair " + std::to_string(k) + " (template_triangle " +
                                                   std::to_string(s.pairs[k].template_triangle) +
                                                   "): the template triangle has zero area");
  }

  // Scan topology: components, unreferenced vertices, degenerate and non-manifold faces (warnings).
  s.num_components = FaceComponents(n, s.scan_faces, &s.component_of_vertex, &s.component_of_face);
  s.setup.num_components = s.num_components;
  for (int v = 0; v < n; ++v)
    if (s.component_of_vertex[v] < 0) s.unreferenced.push_back(v);
  if (!s.unreferenced.empty())
    s.setup.warnings.push_back(std::to_string(s.unreferenced.size()) +
                               " scan vertices belong to no face; they follow the mean translation");
  {
    int degenerate = 0;
    std::map<std::pair<int, int>, int> edge_count;
    for (int f = 0; f < scan.num_faces(); ++f) {
      const Eigen::Vector3d a = s.scan_vertices.row(s.scan_faces(f, 0)), b = s.scan_vertices.row(s.scan_faces(f, 1)),
                            c = s.scan_vertices.row(s.scan_faces(f, 2));
      const double scale = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), (c - b).squaredNorm()});
      if (!((b - a).cross(c - a).norm() > 1e-12 * scale)) ++degenerate;
      for (int k = 0; k < 3; ++k) {
        int i = s.scan_faces(f, k), j = s.scan_faces(f, (k + 1) % 3);
        if (i > j) std::swap(i, j);
        ++edge_count[{i, j}];
      }
    }
    int non_manifold = 0;
    for (const auto& [edge, count] : edge_count) non_manifold += count > 2;
    if (degenerate > 0)
      s.setup.warnings.push_back(std::to_string(degenerate) +
                                 " scan faces have (near) zero area; their weights are mollified");
    if (non_manifold > 0)
      s.setup.warnings.push_back(std::to_string(non_manifold) +
                                 " scan edges are shared by more than two faces (non-manifold)");
  }
  std::vector<int> pairs_in_component(s.num_components, 0);
  for (const CorrespondencePair& pair : s.pairs) ++pairs_in_component[s.component_of_face[pair.scan_triangle]];
  for (int c = 0; c < s.num_components; ++c)
    if (pairs_in_component[c] == 0) {
      int faces = 0, first = -1;
      for (int f = 0; f < scan.num_faces(); ++f)
        if (s.component_of_face[f] == c) {
          if (first < 0) first = f;
          ++faces;
        }
      const Eigen::Vector3d p = s.scan_vertices.row(s.scan_faces(first, 0));
      char where[96];
      std::snprintf(where, sizeof(where), "(%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
      throw InputError(scan_source, "connected component " + std::to_string(c) + " (" + std::to_string(faces) +
                                        " faces, first face " + std::to_string(first) + " near " + where +
                                        ") has no correspondence triangle; every part of the scan needs one");
    }

  // Pair geometry and the sign-alignment spanning tree (Prim over scan centroid distances).
  for (const CorrespondencePair& pair : s.pairs) {
    s.scan_centroid_ref.push_back(Corners(s.scan_vertices, s.scan_faces, pair.scan_triangle).colwise().mean().transpose());
    s.template_centroid_ref.push_back(
        Corners(s.template_reference, s.template_faces, pair.template_triangle).colwise().mean().transpose());
  }
  {
    std::vector<double> best(m, std::numeric_limits<double>::infinity());
    std::vector<int> parent(m, -1);
    std::vector<char> done(m, 0);
    best[0] = 0.0;
    for (int step = 0; step < m; ++step) {
      int next = -1;
      for (int k = 0; k < m; ++k)
        if (!done[k] && (next < 0 || best[k] < best[next])) next = k;
      done[next] = 1;
      s.align_order.push_back(next);
      for (int k = 0; k < m; ++k) {
        if (done[k]) continue;
        const double d = (s.scan_centroid_ref[k] - s.scan_centroid_ref[next]).squaredNorm();
        if (d < best[k]) {
          best[k] = d;
          parent[k] = next;
        }
      }
    }
    s.align_parent = parent;
  }

  // Laplacian; vertices used by no face get a unit diagonal so both systems stay definite.
  s.weights = CotangentWeights(s.scan_vertices, s.scan_faces, options.laplacian);
  Eigen::SparseMatrix<double> laplacian = AssembleLaplacian(n, s.scan_faces, s.weights);
  {
    std::vector<Eigen::Triplet<double>> diagonal;
    for (int v : s.unreferenced) diagonal.emplace_back(v, v, 1.0);
    Eigen::SparseMatrix<double> extra(n, n);
    extra.setFromTriplets(diagonal.begin(), diagonal.end());
    laplacian += extra;
  }

  // Harmonic system: Dirichlet values at the correspondence triangles' vertices.
  std::vector<int> constrained_index(n, -1), constrained;
  {
    std::vector<Eigen::Triplet<double>> entries;
    std::vector<double> weight_sum;
    for (int k = 0; k < m; ++k)
      for (int c = 0; c < 3; ++c) {
        const int v = s.scan_faces(s.pairs[k].scan_triangle, c);
        if (constrained_index[v] < 0) {
          constrained_index[v] = static_cast<int>(constrained.size());
          constrained.push_back(v);
          weight_sum.push_back(0.0);
        }
        entries.emplace_back(constrained_index[v], k, s.pairs[k].weight);
        weight_sum[constrained_index[v]] += s.pairs[k].weight;
      }
    for (auto& entry : entries) entry = Eigen::Triplet<double>(entry.row(), entry.col(), entry.value() / weight_sum[entry.row()]);
    s.average.resize(static_cast<int>(constrained.size()), m);
    s.average.setFromTriplets(entries.begin(), entries.end());
  }
  s.setup.num_constrained_vertices = static_cast<int>(constrained.size());
  if (!s.harmonic.Factor(laplacian, constrained, options.threads, options.single_precision_solves))
    throw InputError(scan_source, "the harmonic interpolation system cannot be factored: " +
                                      s.harmonic.factor.message());
  s.setup.harmonic_factor_nonzeros = s.harmonic.factor.factor_nonzeros();
  if (options.slerp_paths) s.laplacian = laplacian;

  // Poisson system: L plus the soft positional constraints, or, without them, L with one vertex
  // per component pinned (the right-hand side sums to zero over each component, so the pin only
  // fixes the translation gauge).
  {
    const double mean_diagonal = laplacian.diagonal().mean();
    std::vector<Eigen::Triplet<double>> pins;
    if (options.position_weight > 0.0) {
      s.position_weight = options.position_weight * mean_diagonal;
      for (int k = 0; k < m; ++k)
        for (int c = 0; c < 3; ++c)
          pins.emplace_back(s.scan_faces(s.pairs[k].scan_triangle, c), s.scan_faces(s.pairs[k].scan_triangle, c),
                            s.position_weight * s.pairs[k].weight);
    } else {
      std::vector<int> pinned(s.num_components, -1);
      for (int v = 0; v < n; ++v) {
        const int c = s.component_of_vertex[v];
        if (c >= 0 && pinned[c] < 0) pinned[c] = v;
      }
      for (int v : pinned) pins.emplace_back(v, v, mean_diagonal);
    }
    Eigen::SparseMatrix<double> pin(n, n);
    pin.setFromTriplets(pins.begin(), pins.end());
    if (s.poisson.Factor(laplacian + pin) != CholeskyStatus::kOk)
      throw InputError(scan_source, "the Poisson system cannot be factored: " + s.poisson.message());
    s.poisson.set_threads(options.threads);
    s.poisson.set_single_precision(options.single_precision_solves && options.position_weight > 0.0);
    s.setup.poisson_factor_nonzeros = s.poisson.factor_nonzeros();
  }

  // The per-frame layout: vertices in the Poisson factor's ordering; per face, its corners'
  // rows and the flux edges g_j, with weights(f, k) * (x_{k+1} - x_{k+2}) added to corner k + 1
  // and subtracted from corner k + 2 after rotation: g_0 = e_2 - e_1, g_1 = e_0 - e_2 and
  // g_2 = e_1 - e_0 = -(g_0 + g_1).
  s.vertex_of_row = s.poisson.permutation();
  s.row_of_vertex.assign(n, 0);
  for (int i = 0; i < n; ++i) s.row_of_vertex[s.vertex_of_row[i]] = i;
  {
    const int num_faces = scan.num_faces();
    std::vector<int> first_row(num_faces);
    for (int f = 0; f < num_faces; ++f)
      first_row[f] = std::min({s.row_of_vertex[s.scan_faces(f, 0)], s.row_of_vertex[s.scan_faces(f, 1)],
                               s.row_of_vertex[s.scan_faces(f, 2)]});
    s.face_of_slot.resize(num_faces);
    for (int f = 0; f < num_faces; ++f) s.face_of_slot[f] = f;
    std::stable_sort(s.face_of_slot.begin(), s.face_of_slot.end(),
                     [&](int a, int b) { return first_row[a] < first_row[b]; });
    s.face_rows.resize(3 * static_cast<std::size_t>(num_faces));
    const int num_blocks = (num_faces + kFaceBlock - 1) / kFaceBlock;
    s.flux_edges.assign(6 * static_cast<std::size_t>(num_blocks) * kFaceBlock, 0.0);
    for (int slot = 0; slot < num_faces; ++slot) {
      const int f = s.face_of_slot[slot];
      Eigen::Vector3d e[3];
      for (int k = 0; k < 3; ++k) {
        s.face_rows[3 * static_cast<std::size_t>(slot) + k] = s.row_of_vertex[s.scan_faces(f, k)];
        e[k] = s.weights(f, k) * (s.scan_vertices.row(s.scan_faces(f, (k + 1) % 3)) -
                                  s.scan_vertices.row(s.scan_faces(f, (k + 2) % 3))).transpose();
      }
      const Eigen::Vector3d g[2] = {e[2] - e[1], e[0] - e[2]};
      double* block = &s.flux_edges[6 * static_cast<std::size_t>(slot / kFaceBlock) * kFaceBlock];
      for (int j = 0; j < 2; ++j)
        for (int c = 0; c < 3; ++c) block[(3 * j + c) * kFaceBlock + slot % kFaceBlock] = g[j](c);
    }
  }

  // Segment weight fields: the harmonic field is linear in the per-segment quaternions.
  if (options.segment_fields) {
    std::map<std::string, int> segment_id;
    bool all_labelled = true;
    for (const CorrespondencePair& pair : s.pairs) {
      if (pair.segment.empty()) all_labelled = false;
      segment_id.emplace(pair.segment, static_cast<int>(segment_id.size()));
    }
    if (all_labelled && static_cast<int>(segment_id.size()) <= options.max_segment_fields) {
      s.num_segments = static_cast<int>(segment_id.size());
      Eigen::SparseMatrix<double> indicator(m, s.num_segments);
      std::vector<Eigen::Triplet<double>> entries;
      for (int k = 0; k < m; ++k) {
        s.segment_of_pair.push_back(segment_id.at(s.pairs[k].segment));
        entries.emplace_back(k, s.segment_of_pair.back(), 1.0);
      }
      indicator.setFromTriplets(entries.begin(), entries.end());
      s.segment_fields.resize(n, s.num_segments);
      s.harmonic.Solve(Eigen::MatrixXd(s.average * indicator), &s.segment_fields, &s.row_of_vertex);
      s.setup.num_segment_fields = s.num_segments;
    }
  }

  s.setup.factor_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

ConfluentMotion::~ConfluentMotion() = default;
ConfluentMotion::ConfluentMotion(ConfluentMotion&&) noexcept = default;
ConfluentMotion& ConfluentMotion::operator=(ConfluentMotion&&) noexcept = default;

const ConfluentMotionSetupSummary& ConfluentMotion::setup_summary() const { return impl_->setup; }
const Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>& ConfluentMotion::face_rotations() const {
  return impl_->previous_face_rotations;
}

void ConfluentMotion::Reset() {
  Impl& s = *impl_;
  s.has_previous = false;
  s.previous_constraints.clear();
  s.previous_full.clear();
  s.previous_reference = -2;
  s.intermediate_frame = -1;
}

RowMatrixX3d ConfluentMotion::Deform(const RowMatrixX3d& template_vertices, DeformSummary* summary_out) {
  Impl& s = *impl_;
  if (template_vertices.rows() != s.template_reference.rows())
    throw std::invalid_argument("template frame has " + std::to_string(template_vertices.rows()) +
                                " vertices, the reference has " + std::to_string(s.template_reference.rows()));
  if (!template_vertices.allFinite()) throw std::invalid_argument("template frame has non-finite coordinates");
  DeformSummary summary;
  summary.frame = s.frame;
  const int m = static_cast<int>(s.pairs.size());
  const int n = static_cast<int>(s.scan_vertices.rows());
  const int num_faces = static_cast<int>(s.scan_faces.rows());

  // 1. Constraint rotations from the reference pose, signs kept consistent: with the previous
  // frame when there is one (so w changes continuously and goes negative past 180 degrees),
  // else along a spanning tree of neighbouring pairs from a root in the w >= 0 hemisphere.
  std::vector<int> degenerate;
  const std::vector<Eigen::Quaterniond> full = s.ConstraintRotations(s.template_reference, template_vertices, &degenerate);
  auto align = [&](const std::vector<Eigen::Quaterniond>& rotations, const std::vector<Eigen::Vector4d>* previous) {
    std::vector<Eigen::Vector4d> q(m);
    for (int k = 0; k < m; ++k) q[k] = ToVector(rotations[k]);
    if (previous != nullptr) {
      for (int k : degenerate) q[k] = (*previous)[k];
      for (int k = 0; k < m; ++k)
        if (q[k].dot((*previous)[k]) < 0.0) q[k] = -q[k];
    } else {
      for (int k : s.align_order) {
        const int parent = s.align_parent[k];
        if (parent < 0 ? q[k](0) < 0.0 : q[k].dot(q[parent]) < 0.0) q[k] = -q[k];
      }
    }
    return q;
  };
  const bool has_history =
      s.options.temporal_signs && s.has_previous && static_cast<int>(s.previous_full.size()) == m;
  const std::vector<Eigen::Vector4d> full_q = align(full, has_history ? &s.previous_full : nullptr);
  if (!degenerate.empty())
    summary.warnings.push_back(std::to_string(degenerate.size()) +
                               " template correspondence triangles are degenerate in this frame");
  // Singularity check (report section 4.3): |w| small means a rotation near 180 degrees; with
  // continuous signs, w < singular_w also catches rotations beyond it.
  double min_w = 1.0;
  summary.min_abs_w = 1.0;
  for (const Eigen::Vector4d& q : full_q) {
    min_w = std::min(min_w, q(0));
    summary.min_abs_w = std::min(summary.min_abs_w, std::abs(q(0)));
  }
  summary.singular = min_w < s.options.singular_w;

  // 2. Choose the reference: the reference pose, or an intermediate one (an earlier frame).
  int reference = -1;
  if (summary.singular && s.options.slerp_paths) {
    s.intermediate_frame = -1;
    summary.slerp_path_vertices = s.UpdateSlerpPaths(full_q, &summary.warnings);
  } else if (summary.singular && s.options.intermediate_reference) {
    bool keep = false;
    if (s.intermediate_frame >= 0) {
      double min_relative_w = 1.0;
      for (const auto& q : s.ConstraintRotations(s.intermediate_template, template_vertices, nullptr))
        min_relative_w = std::min(min_relative_w, std::abs(q.w()));
      keep = min_relative_w >= s.options.singular_w;
    }
    if (!keep && s.has_previous) {
      s.intermediate_frame = s.frame - 1;
      s.intermediate_template = s.previous_template;
      s.intermediate_face_rotations = s.previous_face_rotations;
      keep = true;
    }
    if (keep)
      reference = s.intermediate_frame;
    else
      summary.warnings.push_back("constraint rotation near 180 degrees (w = " + std::to_string(min_w) +
                                 ") and no earlier frame to use as an intermediate reference");
  } else if (!summary.singular) {
    s.intermediate_frame = -1;
  }
  summary.reference_frame = reference;
  std::vector<Eigen::Vector4d> q;
  if (reference < 0) {
    q = full_q;
  } else {
    degenerate.clear();
    const auto relative = s.ConstraintRotations(s.intermediate_template, template_vertices, &degenerate);
    const bool same = s.options.temporal_signs && s.previous_reference == reference &&
                      static_cast<int>(s.previous_constraints.size()) == m;
    q = align(relative, same ? &s.previous_constraints : nullptr);
  }

  // 4. Harmonic interpolation of the 4 components (Dirichlet values at the constrained vertices),
  // into vertex_q by row (the Poisson factor's ordering).
  const bool threaded = s.options.threads > 1;
  RowMatrixX4d& vertex_q = s.vertex_q;
  vertex_q.resize(n, 4);
  bool use_fields = s.num_segments > 0 && summary.slerp_path_vertices == 0;
  RowMatrixX4d segment_q;
  if (use_fields) {
    segment_q.setZero(s.num_segments, 4);
    for (int k = 0; k < m; ++k) segment_q.row(s.segment_of_pair[k]) += s.pairs[k].weight * q[k].transpose();
    for (int g = 0; g < s.num_segments; ++g) segment_q.row(g).normalize();
    const double min_dot = std::cos(0.5 * s.options.segment_rigid_tolerance_rad);
    for (int k = 0; k < m && use_fields; ++k)
      if (segment_q.row(s.segment_of_pair[k]).dot(q[k].transpose()) < min_dot - 1e-12) use_fields = false;
  }
  summary.used_segment_fields = use_fields;
  if (use_fields) {
    ForHalves(&s.helper, threaded && n >= kMinParallelItems, n, [&](int begin, int end, int) {
      MixFields(s.segment_fields.data(), s.num_segments, segment_q.data(), begin, end, vertex_q.data());
    });
  } else {
    Eigen::MatrixXd constraint_q(m, 4);
    for (int k = 0; k < m; ++k) constraint_q.row(k) = q[k].transpose();
    if (summary.slerp_path_vertices == 0) {
      s.harmonic.Solve(Eigen::MatrixXd(s.average * constraint_q), &vertex_q, &s.row_of_vertex);
    } else {
      const int num_given = static_cast<int>(s.harmonic.constrained.size());
      Eigen::MatrixXd values(num_given + s.path_vertices_at.size(), 4);
      values.topRows(num_given) = s.average * constraint_q;
      for (std::size_t i = 0; i < s.path_vertices_at.size(); ++i) {
        Eigen::Vector4d sum = Eigen::Vector4d::Zero();
        for (int p : s.path_vertices_at[i]) {
          const PathVertex& path = s.path_vertices[p];
          sum += Slerp(q[path.from_pair], q[path.to_pair], path.t);
        }
        values.row(num_given + i) = sum.transpose() / s.path_vertices_at[i].size();
      }
      s.path_harmonic.Solve(values, &vertex_q, &s.row_of_vertex);
    }
  }

  // 5. Per-face rotation: normalised average of the corner quaternions (composed with the
  // intermediate reference's rotation), then the right-hand side U_reduced: the cotangent
  // Laplacian of the fragmented mesh of rotated reference triangles, summed per vertex. Faces
  // are split over the threads; the helper sums into a right-hand side of its own.
  RowMatrixX4d& face_q = s.next_face_rotations;
  face_q.resize(num_faces, 4);
  double* rhs = Aligned32(&s.rhs_storage, 4 * static_cast<std::size_t>(n));
  const bool split_faces = threaded && num_faces >= kMinParallelItems;
  double* partial = split_faces ? Aligned32(&s.partial_storage, 4 * static_cast<std::size_t>(n)) : nullptr;
  FaceAssembly assembly;
  assembly.num_faces = num_faces;
  assembly.face = s.face_of_slot.data();
  assembly.corners = s.face_rows.data();
  assembly.flux_edges = s.flux_edges.data();
  assembly.vertex_q = vertex_q.data();
  assembly.previous = s.has_previous ? s.previous_face_rotations.data() : nullptr;
  assembly.intermediate = reference >= 0 ? s.intermediate_face_rotations.data() : nullptr;
  int vanishing_in[2] = {0, 0};
  const int num_blocks = (num_faces + kFaceBlock - 1) / kFaceBlock;
  ForHalves(&s.helper, split_faces, num_blocks, [&](int begin, int end, int part) {
    double* out = part == 0 ? rhs : partial;
    std::fill(out, out + 4 * static_cast<std::size_t>(n), 0.0);
    vanishing_in[part] = AssembleFaces(assembly, begin, end, face_q.data(), out);
  });
  if (split_faces)
    for (std::size_t i = 0; i < 4 * static_cast<std::size_t>(n); ++i) rhs[i] += partial[i];
  const int vanishing = vanishing_in[0] + vanishing_in[1];
  if (vanishing > 0)
    summary.warnings.push_back(std::to_string(vanishing) +
                               " faces got a vanishing interpolated quaternion (kept their previous rotation)");
  for (int v : s.unreferenced)
    for (int c = 0; c < 4; ++c) rhs[4 * static_cast<std::size_t>(s.row_of_vertex[v]) + c] = 0.0;

  // 6. Where the template's triangles carry the correspondence triangles: the scan-template
  // offset rotates with the template triangle.
  std::vector<Eigen::Vector3d> target(m), template_now(m);
  for (int k = 0; k < m; ++k) {
    template_now[k] =
        Corners(template_vertices, s.template_faces, s.pairs[k].template_triangle).colwise().mean().transpose();
    target[k] = template_now[k] + full[k] * (s.scan_centroid_ref[k] - s.template_centroid_ref[k]);
  }
  if (s.position_weight > 0.0)
    for (int k = 0; k < m; ++k)
      for (int c = 0; c < 3; ++c) {
        const int v = s.scan_faces(s.pairs[k].scan_triangle, c);
        const Eigen::Vector3d corner_target =
            template_now[k] + full[k] * (s.scan_vertices.row(v).transpose() - s.template_centroid_ref[k]);
        Eigen::Map<Eigen::Vector3d>(rhs + 4 * static_cast<std::size_t>(s.row_of_vertex[v])) +=
            (s.position_weight * s.pairs[k].weight) * corner_target;
      }

  // 7. Solve L x = U_reduced (plus the positional terms) with the factor computed once, in place.
  s.poisson.SolvePermuted4(rhs);
  auto solved = [&](int v) { return Eigen::Map<const Eigen::Vector3d>(rhs + 4 * static_cast<std::size_t>(s.row_of_vertex[v])); };
  auto solved_centroid = [&](int f) {
    return Eigen::Vector3d((solved(s.scan_faces(f, 0)) + solved(s.scan_faces(f, 1)) + solved(s.scan_faces(f, 2))) / 3.0);
  };

  // 8. Global position: per component, the translation that best places the correspondence
  // centroids at their targets (zero up to round-off with positional constraints).
  std::vector<Eigen::Vector3d> shift(s.num_components, Eigen::Vector3d::Zero());
  std::vector<double> weight(s.num_components, 0.0);
  Eigen::Vector3d mean_offset = Eigen::Vector3d::Zero();
  for (int k = 0; k < m; ++k) {
    const Eigen::Vector3d scan_now = solved_centroid(s.pairs[k].scan_triangle);
    const int c = s.component_of_face[s.pairs[k].scan_triangle];
    shift[c] += s.pairs[k].weight * (target[k] - scan_now);
    weight[c] += s.pairs[k].weight;
    mean_offset += (target[k] - s.scan_centroid_ref[k]) / m;
  }
  for (int c = 0; c < s.num_components; ++c) shift[c] /= weight[c];
  RowMatrixX3d result(n, 3);
  double non_finite = 0.0;  // becomes NaN when any coordinate is not finite
  for (int v = 0; v < n; ++v) {
    const int c = s.component_of_vertex[v];
    const double* x = rhs + 4 * static_cast<std::size_t>(s.row_of_vertex[v]);
    for (int j = 0; j < 3; ++j) {
      const double value = c >= 0 ? x[j] + shift[c](j) : s.scan_vertices(v, j) + mean_offset(j);
      result(v, j) = value;
      non_finite += value - value;
    }
  }
  double squared = 0.0;
  for (int k = 0; k < m; ++k) {
    const Eigen::Vector3d scan_now = Corners(result, s.scan_faces, s.pairs[k].scan_triangle).colwise().mean().transpose();
    squared += (target[k] - scan_now).squaredNorm();
  }
  summary.placement_rms_m = std::sqrt(squared / m);
  if (non_finite != 0.0) {  // cannot happen with finite input; never hand out NaN
    summary.warnings.push_back("non-finite result replaced by the reference pose");
    for (int v = 0; v < n; ++v)
      if (!result.row(v).allFinite()) result.row(v) = s.scan_vertices.row(v);
  }

  // 9. State for the next frame.
  s.has_previous = true;
  s.previous_template = template_vertices;
  s.previous_constraints = q;
  s.previous_full = full_q;
  s.previous_reference = reference;
  s.previous_face_rotations.swap(face_q);  // face_q is s.next_face_rotations
  ++s.frame;
  if (summary_out) *summary_out = summary;
  return result;
}

}  // namespace confluent
