#include "deform/cholmod_solver.h"

#include <cholmod.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>

namespace confluent {

struct SparseCholesky::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  // Reusable workspace of cholmod_solve2.
  cholmod_dense* solution = nullptr;
  cholmod_dense* work_y = nullptr;
  cholmod_dense* work_e = nullptr;
  std::string message;
  int n = 0;

  Impl() {
    cholmod_start(&common);
    common.print = 0;                // libraries never print
    common.error_handler = nullptr;
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.final_ll = 1;             // keep L L^T (supernodal gives it anyway)
    common.nmethods = 3;             // try AMD, METIS and nested dissection; keep the sparsest factor
  }
  ~Impl() {
    FreeFactor();
    cholmod_finish(&common);
  }
  void FreeFactor() {
    if (factor) cholmod_free_factor(&factor, &common);
    if (solution) cholmod_free_dense(&solution, &common);
    if (work_y) cholmod_free_dense(&work_y, &common);
    if (work_e) cholmod_free_dense(&work_e, &common);
    factor = nullptr;
    solution = work_y = work_e = nullptr;
    n = 0;
  }
};

SparseCholesky::SparseCholesky() : impl_(std::make_unique<Impl>()) {}
SparseCholesky::~SparseCholesky() = default;
SparseCholesky::SparseCholesky(SparseCholesky&&) noexcept = default;
SparseCholesky& SparseCholesky::operator=(SparseCholesky&&) noexcept = default;

CholeskyStatus SparseCholesky::Factor(const Eigen::SparseMatrix<double>& matrix) {
  Impl& s = *impl_;
  s.FreeFactor();
  s.message.clear();
  if (matrix.rows() != matrix.cols()) {
    s.message = "matrix is not square (" + std::to_string(matrix.rows()) + " x " + std::to_string(matrix.cols()) + ")";
    return CholeskyStatus::kNotSquare;
  }
  const int n = static_cast<int>(matrix.rows());
  Eigen::SparseMatrix<double> lower = matrix.triangularView<Eigen::Lower>();
  lower.makeCompressed();
  for (int i = 0; i < lower.nonZeros(); ++i)
    if (!std::isfinite(lower.valuePtr()[i])) {
      s.message = "matrix has non-finite entries";
      return CholeskyStatus::kNumericalFailure;
    }
  cholmod_sparse* a = cholmod_allocate_sparse(n, n, lower.nonZeros(), /*sorted=*/1, /*packed=*/1,
                                              /*stype=*/-1, CHOLMOD_REAL, &s.common);
  if (a == nullptr) {
    s.message = "CHOLMOD could not allocate the matrix";
    return CholeskyStatus::kNumericalFailure;
  }
  std::memcpy(a->p, lower.outerIndexPtr(), sizeof(int) * (n + 1));
  std::memcpy(a->i, lower.innerIndexPtr(), sizeof(int) * lower.nonZeros());
  std::memcpy(a->x, lower.valuePtr(), sizeof(double) * lower.nonZeros());
  s.factor = cholmod_analyze(a, &s.common);
  if (s.factor == nullptr || s.common.status < CHOLMOD_OK) {
    cholmod_free_sparse(&a, &s.common);
    s.FreeFactor();
    s.message = "CHOLMOD analysis failed (status " + std::to_string(s.common.status) + ")";
    return CholeskyStatus::kNumericalFailure;
  }
  const int ok = cholmod_factorize(a, s.factor, &s.common);
  cholmod_free_sparse(&a, &s.common);
  if (s.common.status == CHOLMOD_NOT_POSDEF || (ok && s.factor->minor < s.factor->n)) {
    s.message = "matrix is not positive definite (failed at column " + std::to_string(s.factor->minor) + " of " +
                std::to_string(n) + ")";
    s.FreeFactor();
    return CholeskyStatus::kNotPositiveDefinite;
  }
  if (!ok || s.common.status < CHOLMOD_OK) {
    s.message = "CHOLMOD factorisation failed (status " + std::to_string(s.common.status) + ")";
    s.FreeFactor();
    return CholeskyStatus::kNumericalFailure;
  }
  // Supernodal factorisation is fastest; for the few right-hand sides of a frame the simplicial
  // triangular solves (which handle up to 4 columns per sweep, without BLAS calls per
  // supernode) are faster, so the factor is converted once.
  s.common.final_ll = 1;
  if (!cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/1, /*to_super=*/0, /*to_packed=*/1, /*to_monotonic=*/1,
                             s.factor, &s.common)) {
    s.message = "CHOLMOD could not convert the factor (status " + std::to_string(s.common.status) + ")";
    s.FreeFactor();
    return CholeskyStatus::kNumericalFailure;
  }
  s.n = n;
  return CholeskyStatus::kOk;
}

Eigen::MatrixXd SparseCholesky::Solve(const Eigen::MatrixXd& rhs) const {
  Impl& s = *impl_;
  if (s.factor == nullptr || rhs.rows() != s.n) std::abort();
  const int k = static_cast<int>(rhs.cols());
  if (k == 0) return Eigen::MatrixXd(s.n, 0);
  cholmod_dense b;
  b.nrow = s.n;
  b.ncol = k;
  b.nzmax = static_cast<std::size_t>(s.n) * k;
  b.d = s.n;
  b.x = const_cast<double*>(rhs.data());  // column-major, leading dimension n
  b.z = nullptr;
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  if (!cholmod_solve2(CHOLMOD_A, s.factor, &b, nullptr, &s.solution, nullptr, &s.work_y, &s.work_e, &s.common))
    std::abort();  // only fails on out-of-memory with a valid factor
  Eigen::MatrixXd result(s.n, k);
  std::memcpy(result.data(), s.solution->x, sizeof(double) * s.n * k);
  return result;
}

bool SparseCholesky::is_factored() const { return impl_ && impl_->factor != nullptr; }
int SparseCholesky::rows() const { return impl_ ? impl_->n : 0; }
double SparseCholesky::factor_nonzeros() const {
  if (!is_factored()) return 0.0;
  return impl_->common.lnz;
}
const std::string& SparseCholesky::message() const { return impl_->message; }

}  // namespace confluent
