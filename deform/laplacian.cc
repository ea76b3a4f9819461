#include "deform/laplacian.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <vector>

#include "core/error.h"

namespace confluent {

void CotanLaplacianOptions::Check() const {
  RequireOption(mollify_factor >= 0.0 && mollify_factor < 1.0, "CotanLaplacianOptions.mollify_factor", mollify_factor,
                "in [0, 1)");
}

namespace {

// Area of a triangle from its side lengths (Kahan's stable Heron formula); 0 when invalid.
double AreaFromLengths(double a, double b, double c) {
  if (a < b) std::swap(a, b);
  if (b < c) std::swap(b, c);
  if (a < b) std::swap(a, b);
  const double p = (a + (b + c)) * (c - (a - b)) * (c + (a - b)) * (a + (b - c));
  return p > 0.0 ? 0.25 * std::sqrt(p) : 0.0;
}

int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

}  // namespace

Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> CotangentWeights(
    const RowMatrixX3d& vertices, const RowMatrixX3i& faces, const CotanLaplacianOptions& options) {
  options.Check();
  const int m = static_cast<int>(faces.rows());
  // lengths(f, k): length of the edge opposite corner k.
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> lengths(m, 3);
  double total = 0.0;
  for (int f = 0; f < m; ++f)
    for (int k = 0; k < 3; ++k) {
      const double l = (vertices.row(faces(f, (k + 1) % 3)) - vertices.row(faces(f, (k + 2) % 3))).norm();
      lengths(f, k) = std::isfinite(l) ? l : 0.0;
      total += lengths(f, k);
    }
  if (m > 0 && options.mollify_factor > 0.0) {
    const double delta = options.mollify_factor * total / (3.0 * m);
    double epsilon = 0.0;
    for (int f = 0; f < m; ++f)
      for (int k = 0; k < 3; ++k)
        epsilon = std::max(epsilon, delta - (lengths(f, (k + 1) % 3) + lengths(f, (k + 2) % 3) - lengths(f, k)));
    lengths.array() += epsilon;
  }
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> weights(m, 3);
  for (int f = 0; f < m; ++f) {
    const double area = AreaFromLengths(lengths(f, 0), lengths(f, 1), lengths(f, 2));
    for (int k = 0; k < 3; ++k) {
      if (!(area > 0.0)) {
        weights(f, k) = 0.0;
        continue;
      }
      const double a = lengths(f, (k + 1) % 3), b = lengths(f, (k + 2) % 3), c = lengths(f, k);
      weights(f, k) = (a * a + b * b - c * c) / (8.0 * area);  // 1/2 cot(angle at corner k)
    }
  }
  return weights;
}

Eigen::SparseMatrix<double> AssembleLaplacian(
    int num_vertices, const RowMatrixX3i& faces,
    const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& weights) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(faces.rows()) * 12);
  for (int f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int i = faces(f, (k + 1) % 3), j = faces(f, (k + 2) % 3);
      if (i == j) continue;
      const double w = weights(f, k);
      triplets.emplace_back(i, j, -w);
      triplets.emplace_back(j, i, -w);
      triplets.emplace_back(i, i, w);
      triplets.emplace_back(j, j, w);
    }
  Eigen::SparseMatrix<double> laplacian(num_vertices, num_vertices);
  laplacian.setFromTriplets(triplets.begin(), triplets.end());
  laplacian.makeCompressed();
  return laplacian;
}

Eigen::SparseMatrix<double> CotanLaplacian(const RowMatrixX3d& vertices, const RowMatrixX3i& faces,
                                           const CotanLaplacianOptions& options) {
  return AssembleLaplacian(static_cast<int>(vertices.rows()), faces, CotangentWeights(vertices, faces, options));
}

Eigen::VectorXd BarycentricVertexAreas(const RowMatrixX3d& vertices, const RowMatrixX3i& faces) {
  Eigen::VectorXd areas = Eigen::VectorXd::Zero(vertices.rows());
  for (int f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = vertices.row(faces(f, 0)), b = vertices.row(faces(f, 1)), c = vertices.row(faces(f, 2));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    if (!std::isfinite(area)) continue;
    for (int k = 0; k < 3; ++k) areas(faces(f, k)) += area / 3.0;
  }
  return areas;
}

int FaceComponents(int num_vertices, const RowMatrixX3i& faces, std::vector<int>* component_of_vertex,
                   std::vector<int>* component_of_face) {
  std::vector<int> parent(num_vertices);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<char> used(num_vertices, 0);
  for (int f = 0; f < faces.rows(); ++f) {
    const int r0 = Find(parent, faces(f, 0));
    used[faces(f, 0)] = used[faces(f, 1)] = used[faces(f, 2)] = 1;
    for (int k = 1; k < 3; ++k) {
      const int r = Find(parent, faces(f, k));
      if (r != Find(parent, r0)) parent[r] = Find(parent, r0);
    }
  }
  int count = 0;
  // Number components in the order of their first face, so ids are stable.
  std::vector<int> root_label(num_vertices, -1);
  if (component_of_face) component_of_face->assign(faces.rows(), -1);
  for (int f = 0; f < faces.rows(); ++f) {
    const int r = Find(parent, faces(f, 0));
    if (root_label[r] < 0) root_label[r] = count++;
    if (component_of_face) (*component_of_face)[f] = root_label[r];
  }
  if (component_of_vertex) {
    component_of_vertex->assign(num_vertices, -1);
    for (int v = 0; v < num_vertices; ++v)
      if (used[v]) (*component_of_vertex)[v] = root_label[Find(parent, v)];
  }
  return count;
}

}  // namespace confluent
