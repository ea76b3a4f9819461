// Cotangent Laplacian and the CHOLMOD factorisation.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "core/mesh_ops.h"
#include "deform/cholmod_solver.h"
#include "deform/laplacian.h"
#include "tests/deform/test_geometry.h"

namespace confluent {
namespace {

// A planar grid in z = 0 with (n+1)^2 vertices, jittered interior vertices.
Mesh MakeGrid(int n, double jitter, unsigned seed) {
  Mesh mesh;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-jitter, jitter);
  mesh.vertices.resize((n + 1) * (n + 1), 3);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const bool interior = i > 0 && j > 0 && i < n && j < n;
      mesh.vertices.row(i * (n + 1) + j) << (j + (interior ? uniform(rng) : 0.0)) / n,
          (i + (interior ? uniform(rng) : 0.0)) / n, 0.0;
    }
  mesh.faces.resize(2 * n * n, 3);
  int f = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.faces.row(f++) << a, b, d;
      mesh.faces.row(f++) << a, d, c;
    }
  return mesh;
}

TEST(CotanLaplacian, SymmetricZeroRowSumsAndLinearPrecision) {
  // Jitter makes many triangles obtuse; the cotangent Laplacian still reproduces linear
  // functions exactly at interior vertices (linear precision of the P1 stiffness matrix).
  const Mesh grid = MakeGrid(12, 0.35, 7);
  CotanLaplacianOptions exact;
  exact.mollify_factor = 0.0;
  const Eigen::SparseMatrix<double> l = CotanLaplacian(grid.vertices, grid.faces, exact);
  const Eigen::MatrixXd dense(l);
  EXPECT_LT((dense - dense.transpose()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((dense * Eigen::VectorXd::Ones(dense.rows())).cwiseAbs().maxCoeff(), 1e-10);
  const Eigen::VectorXd linear = 0.3 * grid.vertices.col(0) - 1.7 * grid.vertices.col(1);
  const Eigen::VectorXd lx = dense * linear;
  for (int i = 1; i < 12; ++i)
    for (int j = 1; j < 12; ++j) EXPECT_NEAR(lx(i * 13 + j), 0.0, 1e-10);
  // Positive semi-definite with exactly one zero eigenvalue (a connected mesh).
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(dense);
  EXPECT_GT(eigen.eigenvalues()(0), -1e-10);
  EXPECT_LT(std::abs(eigen.eigenvalues()(0)), 1e-10);
  EXPECT_GT(eigen.eigenvalues()(1), 1e-6);
}

TEST(CotanLaplacian, DegenerateTrianglesGiveFiniteSemiDefiniteMatrix) {
  Mesh grid = MakeGrid(6, 0.0, 1);
  // Collapse one interior vertex onto its neighbour (two zero-area faces) and add a repeated-index face.
  grid.vertices.row(3 * 7 + 3) = grid.vertices.row(3 * 7 + 4);
  grid.faces.conservativeResize(grid.faces.rows() + 1, 3);
  grid.faces.row(grid.faces.rows() - 1) << 10, 10, 11;
  const auto weights = CotangentWeights(grid.vertices, grid.faces);
  EXPECT_TRUE(weights.allFinite());
  const Eigen::MatrixXd dense(CotanLaplacian(grid.vertices, grid.faces));
  ASSERT_TRUE(dense.allFinite());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(dense);
  EXPECT_GT(eigen.eigenvalues()(0), -1e-9 * eigen.eigenvalues().maxCoeff());
}

TEST(CotanLaplacian, ComponentsAndAreas) {
  Mesh a = testing::MakeTube(0.1, 1.0, 4, 6);
  const double area = BarycentricVertexAreas(a.vertices, a.faces).sum();
  EXPECT_NEAR(area, FaceAreas(a).sum(), 1e-12);
  Mesh two = a;
  const int n = a.num_vertices();
  two.vertices.conservativeResize(2 * n + 1, 3);
  two.vertices.block(n, 0, n, 3) = a.vertices.rowwise() + Eigen::RowVector3d(1, 0, 0);
  two.vertices.row(2 * n) << 5, 5, 5;  // unreferenced
  two.faces.conservativeResize(2 * a.num_faces(), 3);
  two.faces.bottomRows(a.num_faces()) = a.faces.array() + n;
  std::vector<int> of_vertex, of_face;
  EXPECT_EQ(FaceComponents(two.num_vertices(), two.faces, &of_vertex, &of_face), 2);
  EXPECT_EQ(of_vertex[0], 0);
  EXPECT_EQ(of_vertex[n], 1);
  EXPECT_EQ(of_vertex[2 * n], -1);
  EXPECT_EQ(of_face.back(), 1);
}

TEST(SparseCholesky, SolvesManyRightHandSides) {
  const Mesh tube = testing::MakeTube(0.05, 0.5, 20, 16);
  Eigen::SparseMatrix<double> a = CotanLaplacian(tube.vertices, tube.faces);
  for (int i = 0; i < a.rows(); i += 7) a.coeffRef(i, i) += 0.5;  // make it definite
  SparseCholesky cholesky;
  ASSERT_EQ(cholesky.Factor(a), CholeskyStatus::kOk) << cholesky.message();
  EXPECT_EQ(cholesky.rows(), a.rows());
  EXPECT_GT(cholesky.factor_nonzeros(), a.rows());
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd rhs(a.rows(), 9);
  for (int i = 0; i < rhs.size(); ++i) rhs.data()[i] = normal(rng);
  for (int repeat = 0; repeat < 2; ++repeat) {  // workspace reuse
    const Eigen::MatrixXd x = cholesky.Solve(rhs);
    EXPECT_LT((a * x - rhs).norm() / rhs.norm(), 1e-10);
  }
  const Eigen::MatrixXd one = cholesky.Solve(rhs.col(4));
  EXPECT_LT((a * one - rhs.col(4)).norm() / rhs.col(4).norm(), 1e-10);
}

// A system large enough for the two-thread schedule (independent elimination subtrees): the
// row-major and column-major solves on one and two threads all solve it, and agree.
TEST(SparseCholesky, RowMajorAndTwoThreadSolvesAgree) {
  const Mesh sphere = MakeUvSphere(0.2, 80, 160);
  Eigen::SparseMatrix<double> a = CotanLaplacian(sphere.vertices, sphere.faces);
  for (int i = 0; i < a.rows(); i += 50) a.coeffRef(i, i) += 1.0;
  SparseCholesky cholesky;
  ASSERT_EQ(cholesky.Factor(a), CholeskyStatus::kOk) << cholesky.message();
  ASSERT_GT(cholesky.factor_nonzeros(), 2e5);
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  for (int k : {1, 2, 3, 6}) {
    Eigen::MatrixXd rhs(a.rows(), k);
    for (int i = 0; i < rhs.size(); ++i) rhs.data()[i] = normal(rng);
    cholesky.set_threads(1);
    const Eigen::MatrixXd serial = cholesky.Solve(rhs);
    EXPECT_LT((a * serial - rhs).norm() / rhs.norm(), 1e-10) << k << " columns";
    cholesky.set_threads(2);
    for (int repeat = 0; repeat < 2; ++repeat) {  // workspace (and deferred sums) reused
      const Eigen::MatrixXd parallel = cholesky.Solve(rhs);
      EXPECT_LT((parallel - serial).norm() / serial.norm(), 1e-12) << k << " columns";
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows = rhs;
      cholesky.SolveRowMajor(rows.data(), k);
      EXPECT_LT((Eigen::MatrixXd(rows) - serial).norm() / serial.norm(), 1e-12) << k << " columns";
    }
  }
}

TEST(SparseCholesky, ReportsNotPositiveDefinite) {
  const Mesh tube = testing::MakeTube(0.05, 0.5, 6, 8);
  SparseCholesky cholesky;
  // The bare Laplacian is singular (constants in its kernel).
  const Eigen::SparseMatrix<double> singular = CotanLaplacian(tube.vertices, tube.faces);
  EXPECT_EQ(cholesky.Factor(singular), CholeskyStatus::kNotPositiveDefinite);
  EXPECT_NE(cholesky.message().find("not positive definite"), std::string::npos) << cholesky.message();
  EXPECT_FALSE(cholesky.is_factored());
  Eigen::SparseMatrix<double> indefinite(3, 3);
  indefinite.insert(0, 0) = 1.0;
  indefinite.insert(1, 1) = -2.0;
  indefinite.insert(2, 2) = 1.0;
  EXPECT_EQ(cholesky.Factor(indefinite), CholeskyStatus::kNotPositiveDefinite);
  EXPECT_EQ(cholesky.Factor(Eigen::SparseMatrix<double>(3, 4)), CholeskyStatus::kNotSquare);
}

}  // namespace
}  // namespace confluent
