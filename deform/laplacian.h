#pragma once
// Cotangent Laplacian of a triangle mesh, robust to obtuse and degenerate triangles.

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "core/mesh.h"

namespace confluent {

// Options for the cotangent weights.
struct CotanLaplacianOptions {
  // Intrinsic mollification (Sharp and Crane 2020, "A Laplacian for Nonmanifold Triangle
  // Meshes"): every edge length is increased by one common epsilon so that each triangle
  // satisfies the triangle inequality with a margin of at least
  // `mollify_factor * mean edge length`. Cotangents are then computed from these intrinsic
  // lengths, so zero-area and needle triangles give large but finite weights and each
  // triangle's stiffness matrix stays positive semi-definite. 0 disables mollification
  // (degenerate triangles then get zero weights).
  double mollify_factor = 1e-4;
  void Check() const;  // throws UsageError naming an invalid field and its value
};

// Per-face half cotangent weights, m x 3: entry (f, k) is 1/2 cot of the (mollified) angle at
// corner k of face f, i.e. the weight of the edge opposite corner k, between corners k+1 and
// k+2 (mod 3). Always finite. Obtuse angles give negative entries.
Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> CotangentWeights(
    const RowMatrixX3d& vertices, const RowMatrixX3i& faces, const CotanLaplacianOptions& options = {});

// Assembles the n x n Laplacian from per-face weights as above: (L x)_i = sum_j w_ij (x_i - x_j),
// so L is symmetric positive semi-definite with the constants of every connected component in
// its kernel (the standard P1 finite-element stiffness matrix; positive diagonal).
Eigen::SparseMatrix<double> AssembleLaplacian(
    int num_vertices, const RowMatrixX3i& faces,
    const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& weights);

// The cotangent Laplacian of (vertices, faces): AssembleLaplacian of CotangentWeights.
Eigen::SparseMatrix<double> CotanLaplacian(const RowMatrixX3d& vertices, const RowMatrixX3i& faces,
                                           const CotanLaplacianOptions& options = {});

// Barycentric vertex areas (a third of each incident face's area), n entries, m^2.
Eigen::VectorXd BarycentricVertexAreas(const RowMatrixX3d& vertices, const RowMatrixX3i& faces);

// Connected components of the faces (faces sharing a vertex are connected). Returns the number
// of components; fills `component_of_vertex` (n, -1 for vertices used by no face) and
// `component_of_face` (m).
int FaceComponents(int num_vertices, const RowMatrixX3i& faces, std::vector<int>* component_of_vertex,
                   std::vector<int>* component_of_face);

}  // namespace confluent
