#pragma once
// INTERNAL (deform/confluent_motion.cc and deform/confluent_motion_deform.cc only): Confluent
// Motion's state (ConfluentMotion::Impl) and the helpers both halves use. Setup (the harmonic and
// Poisson systems, pairs, segment fields) is in confluent_motion.cc; the per-frame Deform, with
// its SLERP paths and constraint rotations, in confluent_motion_deform.cc.

#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <string>
#include <utility>
#include <vector>

#include "deform/cholmod_solver.h"
#include "deform/confluent_motion.h"
#include "deform/helper_thread.h"
#include "deform/motion_kernels.h"

namespace confluent {
namespace confluent_motion_internal {

using deform_internal::Aligned32;
using deform_internal::AssembleFaces;
using deform_internal::FaceAssembly;
using deform_internal::kFaceBlock;
using deform_internal::MixFields;
using RowMatrixX4d = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;
using Weights = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// Rotation that best maps triangle `from` onto triangle `to` (Kabsch: the rotation part of the
// polar decomposition of the cross-covariance of centred corners plus the scaled normal).
// Returns false (and the identity) for a degenerate triangle.
bool TriangleRotation(const Eigen::Matrix3d& from, const Eigen::Matrix3d& to, Eigen::Quaterniond* rotation);

Eigen::Matrix3d Corners(const RowMatrixX3d& vertices, const RowMatrixX3i& faces, int f);

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

// One scan vertex on a SLERP path: its quaternion is Slerp(q[from_pair], q[to_pair], t).
struct PathVertex {
  int vertex = -1;
  int from_pair = -1;  // the well-conditioned pair the path starts at
  int to_pair = -1;    // the near-180-degree pair it ends at
  double t = 0.0;
};

}  // namespace confluent_motion_internal

using confluent_motion_internal::Aligned32;
using confluent_motion_internal::AssembleFaces;
using confluent_motion_internal::Corners;
using confluent_motion_internal::DirichletSystem;
using confluent_motion_internal::FaceAssembly;
using confluent_motion_internal::kFaceBlock;
using confluent_motion_internal::MixFields;
using confluent_motion_internal::PathVertex;
using confluent_motion_internal::RowMatrixX4d;
using confluent_motion_internal::TriangleRotation;
using confluent_motion_internal::Weights;

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
  int UpdateSlerpPaths(const std::vector<Eigen::Vector4d>& q, std::vector<std::string>* warnings);

  std::vector<Eigen::Quaterniond> ConstraintRotations(const RowMatrixX3d& from, const RowMatrixX3d& to,
                                                      std::vector<int>* degenerate) const;
};

}  // namespace confluent
