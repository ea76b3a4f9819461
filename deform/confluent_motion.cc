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
#include "deform/confluent_motion_impl.h"

namespace confluent {

void ConfluentMotionOptions::Check() const {
  laplacian.Check();
  const std::string owner = "ConfluentMotionOptions.";
  RequireOption(singular_w >= 0.0 && singular_w < 1.0, owner + "singular_w", singular_w, "in [0, 1)");
  RequireOption(max_segment_fields >= 1, owner + "max_segment_fields", max_segment_fields, ">= 1");
  RequireOption(segment_rigid_tolerance_rad >= 0.0, owner + "segment_rigid_tolerance_rad", segment_rigid_tolerance_rad,
                ">= 0");
  RequireOption(position_weight >= 0.0, owner + "position_weight", position_weight, ">= 0");
  RequireOption(threads >= 1, owner + "threads", threads, ">= 1");
}

namespace confluent_motion_internal {

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

Eigen::Matrix3d Corners(const RowMatrixX3d& vertices, const RowMatrixX3i& faces, int f) {
  Eigen::Matrix3d corners;
  for (int k = 0; k < 3; ++k) corners.row(k) = vertices.row(faces(f, k));
  return corners;
}

}  // namespace confluent_motion_internal

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

}  // namespace confluent
