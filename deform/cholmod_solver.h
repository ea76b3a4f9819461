#pragma once
// Sparse Cholesky factorisation (CHOLMOD, supernodal) that is computed once and then solves many
// right-hand sides. CHOLMOD types stay in the .cc.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

namespace confluent {

// Outcome of SparseCholesky::Factor.
enum class CholeskyStatus {
  kOk,
  kNotSquare,             // the matrix is not square
  kNotPositiveDefinite,   // a non-positive pivot was met (singular or indefinite matrix)
  kNumericalFailure,      // CHOLMOD failed otherwise (out of memory, non-finite entries)
};

// Factors a symmetric positive definite sparse matrix A = L L^T once (fill-reducing ordering,
// supernodal) and solves A X = B for dense B with many columns. Only the lower triangle of A
// is read. Solve() reuses workspace, so one object must not be used from two threads at once;
// with set_threads(2) one Solve() itself splits the triangular solves over two threads
// (independent subtrees of the elimination tree; the second thread is kept between solves).
class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(SparseCholesky&&) noexcept;
  SparseCholesky& operator=(SparseCholesky&&) noexcept;
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  // Analyses and factors `matrix` (n x n). Returns kOk on success; otherwise the object holds no
  // factor and message() says why (e.g. "not positive definite: pivot 17 of 100").
  CholeskyStatus Factor(const Eigen::SparseMatrix<double>& matrix);

  // Solves A X = B for B of size n x k (any k >= 1). Aborts if no factor is held.
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& rhs) const;

  // Solves A X = B in place for B of size n x k stored row-major (k values per row, any k >= 1),
  // without allocating once the workspace exists. Aborts if no factor is held.
  void SolveRowMajor(double* rhs_in_solution_out, int k) const;

  // The fill-reducing ordering: row i of the factored system is row permutation()[i] of A
  // (n entries; empty without a factor).
  const std::vector<int>& permutation() const;

  // Solves A X = B in place for 4 right-hand sides given row-major in the factor's ordering:
  // row i of `data` (4 doubles; fastest when `data` is 32-byte aligned) holds row
  // permutation()[i] of B on entry and of X on return. Saves SolveRowMajor's reordering when the
  // caller assembles B in that order. Aborts if no factor is held.
  void SolvePermuted4(double* data) const;

  // Solves with the factor rounded to single precision (arithmetic stays double): half the
  // memory traffic, relative error about 1e-7 times the condition number. Default false.
  void set_single_precision(bool single);

  // Threads that one Solve() may use (1 = the calling thread only; default 1). Small systems
  // are solved on one thread regardless.
  void set_threads(int threads);

  bool is_factored() const;
  int rows() const;                   // n, or 0 without a factor
  double factor_nonzeros() const;     // entries in L (fill-in measure), 0 without a factor
  const std::string& message() const;  // why the last Factor() failed; empty on success

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace confluent
