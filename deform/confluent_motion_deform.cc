// Confluent Motion per frame: ConfluentMotion::Deform (constraint rotations, sign alignment, the
// harmonic and SLERP-path rotation fields, the Poisson solve) and the SLERP paths it rebuilds.

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <map>
#include <queue>
#include <stdexcept>

#include "core/error.h"
#include "deform/confluent_motion_impl.h"

namespace confluent {

namespace {

Eigen::Vector4d ToVector(const Eigen::Quaterniond& q) { return Eigen::Vector4d(q.w(), q.x(), q.y(), q.z()); }

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

// Spherical linear interpolation from a (t = 0) to b (t = 1) along the great circle through
// them as given (no sign flip: with continuous signs the long way round is the intended one).
Eigen::Vector4d Slerp(const Eigen::Vector4d& a, const Eigen::Vector4d& b, double t) {
  const double cosine = std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0);
  const double angle = std::acos(cosine);
  if (std::sin(angle) < 1e-6) return ((1.0 - t) * a + t * b).normalized();  // (anti)parallel
  return (std::sin((1.0 - t) * angle) * a + std::sin(t * angle) * b) / std::sin(angle);
}

}  // namespace

int ConfluentMotion::Impl::UpdateSlerpPaths(const std::vector<Eigen::Vector4d>& q, std::vector<std::string>* warnings) {
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

std::vector<Eigen::Quaterniond> ConfluentMotion::Impl::ConstraintRotations(const RowMatrixX3d& from,
                                                                           const RowMatrixX3d& to,
                                                                           std::vector<int>* degenerate) const {
  std::vector<Eigen::Quaterniond> result(pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const int t = pairs[k].template_triangle;
    if (!TriangleRotation(Corners(from, template_faces, t), Corners(to, template_faces, t), &result[k]) && degenerate)
      degenerate->push_back(static_cast<int>(k));
  }
  return result;
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
