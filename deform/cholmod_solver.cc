#include "deform/cholmod_solver.h"

#include <cholmod.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "deform/helper_thread.h"

namespace confluent {

namespace {

// Below this many stored factor entries a solve stays on one thread (starting one costs more).
constexpr double kMinParallelEntries = 150000.0;

}  // namespace

// A view of CHOLMOD's supernodal factor (outside the anonymous namespace: SparseCholesky::Impl
// holds one): supernode s covers the columns
// [first_col[s], first_col[s + 1]); its rows (its own columns first, then the rows below,
// ascending) are rows[row_start[s] .. row_start[s + 1]), and its values are a column-major block
// with leading dimension equal to its row count, at values + value_start[s].
namespace cholmod_solver_internal {
struct SupernodalView {
  int count = 0;
  const int* first_col = nullptr;
  const int* row_start = nullptr;
  const int* value_start = nullptr;
  const int* rows = nullptr;
  const double* values = nullptr;
  const double* inverse_diagonal = nullptr;  // per column, 1 / L(j, j): a multiply instead of a divide
  const float* float_values = nullptr;       // values rounded to single precision, or null
};
}  // namespace cholmod_solver_internal
using cholmod_solver_internal::SupernodalView;

namespace {

template <typename T>
const T* Values(const SupernodalView& f);
template <>
const double* Values<double>(const SupernodalView& f) { return f.values; }
template <>
const float* Values<float>(const SupernodalView& f) { return f.float_values; }

// Row-major blocks of R right-hand sides are handled as one vector per row (GCC vector
// extensions): every buffer they touch starts at a 32-byte boundary (see Aligned).
typedef double Vec2 __attribute__((vector_size(16)));
typedef double Vec4 __attribute__((vector_size(32)));

// A buffer of at least `size` doubles starting at a 32-byte boundary, inside `storage`.
double* Aligned(std::vector<double>* storage, std::size_t size) {
  if (storage->size() < size + 4) storage->assign(size + 4, 0.0);
  const std::uintptr_t address = reinterpret_cast<std::uintptr_t>(storage->data());
  return storage->data() + ((32 - address % 32) % 32) / sizeof(double);
}

// Forward substitution with supernode s on y (n x R, row-major; V holds R doubles). Rows below
// the supernode up to `direct_rows` (counted from the supernode's first row) are updated in y;
// the others are accumulated in `deferred` (indexed by deferred_index[row]), so that two
// threads can work on disjoint subtrees.
template <typename V, typename T>
inline __attribute__((always_inline)) void ForwardSupernodeT(const SupernodalView& f, int s, double* y_data,
                                                              double* acc_data, int direct_rows,
                                                              double* deferred_data, const int* deferred_index) {
  V* y = reinterpret_cast<V*>(y_data);
  V* acc = reinterpret_cast<V*>(acc_data);
  const int k1 = f.first_col[s], num_cols = f.first_col[s + 1] - k1;
  const int num_rows = f.row_start[s + 1] - f.row_start[s];
  const T* block = Values<T>(f) + f.value_start[s];
  const double* inverse_diagonal = f.inverse_diagonal + k1;
  V* yd = y + k1;
  for (int j = 0; j < num_cols; ++j) {
    const T* col = block + static_cast<std::size_t>(j) * num_rows;
    const V xj = yd[j] * inverse_diagonal[j];
    yd[j] = xj;
    for (int i = j + 1; i < num_cols; ++i) yd[i] -= col[i] * xj;
  }
  const int below = num_rows - num_cols;
  if (below == 0) return;
  {
    const T* col = block + num_cols;
    const V xj = yd[0];
    for (int i = 0; i < below; ++i) acc[i] = col[i] * xj;
  }
  int j = 1;
  for (; j + 1 < num_cols; j += 2) {  // two columns per pass over acc
    const T* col0 = block + static_cast<std::size_t>(j) * num_rows + num_cols;
    const T* col1 = col0 + num_rows;
    const V x0 = yd[j], x1 = yd[j + 1];
    for (int i = 0; i < below; ++i) acc[i] += col0[i] * x0 + col1[i] * x1;
  }
  if (j < num_cols) {
    const T* col = block + static_cast<std::size_t>(j) * num_rows + num_cols;
    const V xj = yd[j];
    for (int i = 0; i < below; ++i) acc[i] += col[i] * xj;
  }
  const int* rows = f.rows + f.row_start[s] + num_cols;
  const int direct = direct_rows - num_cols;
  for (int i = 0; i < direct; ++i) y[rows[i]] -= acc[i];
  V* deferred = reinterpret_cast<V*>(deferred_data);
  for (int i = direct; i < below; ++i) deferred[deferred_index[rows[i]]] += acc[i];
}

// Backward substitution (L^T) with supernode s on x (n x R, row-major); `gathered` is scratch.
template <typename V, typename T>
inline __attribute__((always_inline)) void BackwardSupernodeT(const SupernodalView& f, int s, double* x_data,
                                                               double* gathered_data) {
  V* x = reinterpret_cast<V*>(x_data);
  V* gathered = reinterpret_cast<V*>(gathered_data);
  const int k1 = f.first_col[s], num_cols = f.first_col[s + 1] - k1;
  const int num_rows = f.row_start[s + 1] - f.row_start[s];
  const T* block = Values<T>(f) + f.value_start[s];
  const int* rows = f.rows + f.row_start[s] + num_cols;
  const int below = num_rows - num_cols;
  for (int i = 0; i < below; ++i) gathered[i] = x[rows[i]];
  V* xd = x + k1;
  const V zero = xd[0] * 0.0;
  for (int j = num_cols - 1; j >= 0; --j) {
    const T* col = block + static_cast<std::size_t>(j) * num_rows;
    // Four partial sums keep the multiply-adds independent.
    V sum0 = zero, sum1 = zero, sum2 = zero, sum3 = zero;
    const T* col_below = col + num_cols;
    int i = 0;
    for (; i + 3 < below; i += 4) {
      sum0 += col_below[i] * gathered[i];
      sum1 += col_below[i + 1] * gathered[i + 1];
      sum2 += col_below[i + 2] * gathered[i + 2];
      sum3 += col_below[i + 3] * gathered[i + 3];
    }
    for (; i < below; ++i) sum0 += col_below[i] * gathered[i];
    i = j + 1;
    for (; i + 1 < num_cols; i += 2) {
      sum1 += col[i] * xd[i];
      sum2 += col[i + 1] * xd[i + 1];
    }
    if (i < num_cols) sum3 += col[i] * xd[i];
    xd[j] = (xd[j] - ((sum0 + sum1) + (sum2 + sum3))) * f.inverse_diagonal[k1 + j];
  }
}

// The kernels for 1, 2 and 4 interleaved right-hand sides (3 is padded to 4), compiled for AVX2
// as well as the baseline instruction set.
#define CONFLUENT_SOLVE_KERNELS(R, V, T, SUFFIX)                                                          \
  __attribute__((target_clones("arch=x86-64-v3", "default"))) void ForwardSupernode##R##SUFFIX(            \
      const SupernodalView& f, int s, double* y, double* acc, int direct_rows, double* deferred,          \
      const int* deferred_index) {                                                                       \
    ForwardSupernodeT<V, T>(f, s, y, acc, direct_rows, deferred, deferred_index);                         \
  }                                                                                                      \
  __attribute__((target_clones("arch=x86-64-v3", "default"))) void BackwardSupernode##R##SUFFIX(           \
      const SupernodalView& f, int s, double* x, double* gathered) {                                     \
    BackwardSupernodeT<V, T>(f, s, x, gathered);                                                          \
  }
CONFLUENT_SOLVE_KERNELS(1, double, double, d)
CONFLUENT_SOLVE_KERNELS(2, Vec2, double, d)
CONFLUENT_SOLVE_KERNELS(4, Vec4, double, d)
CONFLUENT_SOLVE_KERNELS(1, double, float, f)
CONFLUENT_SOLVE_KERNELS(2, Vec2, float, f)
CONFLUENT_SOLVE_KERNELS(4, Vec4, float, f)
#undef CONFLUENT_SOLVE_KERNELS

template <int R>
void ForwardSupernode(const SupernodalView& f, int s, double* y, double* acc, int direct_rows, double* deferred,
                      const int* deferred_index) {
  const bool single = f.float_values != nullptr;
  if constexpr (R == 1) (single ? ForwardSupernode1f : ForwardSupernode1d)(f, s, y, acc, direct_rows, deferred, deferred_index);
  else if constexpr (R == 2) (single ? ForwardSupernode2f : ForwardSupernode2d)(f, s, y, acc, direct_rows, deferred, deferred_index);
  else (single ? ForwardSupernode4f : ForwardSupernode4d)(f, s, y, acc, direct_rows, deferred, deferred_index);
}
template <int R>
void BackwardSupernode(const SupernodalView& f, int s, double* x, double* gathered) {
  const bool single = f.float_values != nullptr;
  if constexpr (R == 1) (single ? BackwardSupernode1f : BackwardSupernode1d)(f, s, x, gathered);
  else if constexpr (R == 2) (single ? BackwardSupernode2f : BackwardSupernode2d)(f, s, x, gathered);
  else (single ? BackwardSupernode4f : BackwardSupernode4d)(f, s, x, gathered);
}

}  // namespace

struct SparseCholesky::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  // Reusable workspace of cholmod_solve2 (only for a simplicial factor).
  cholmod_dense* solution = nullptr;
  cholmod_dense* work_y = nullptr;
  cholmod_dense* work_e = nullptr;
  std::string message;
  int n = 0;
  int threads = 1;
  std::vector<int> permutation;  // of the factor (identity for a simplicial one)
  HelperThread helper;           // the second thread of parallel solves

  // Supernodal solves.
  SupernodalView view;
  std::vector<double> inverse_diagonal;
  std::vector<float> float_values;  // with single precision: the factor rounded
  bool single_precision = false;
  int max_rows = 0;
  // Two-thread schedule: per thread, subtrees as ranges [begin, end) of supernodes (a subtree
  // is contiguous in CHOLMOD's postorder); the supernodes above them run on one thread.
  bool parallel = false;
  std::vector<std::pair<int, int>> ranges[2];
  std::vector<int> top;            // ascending
  std::vector<int> top_columns;    // columns of the top supernodes
  std::vector<int> direct_rows;    // per supernode: leading rows inside its own subtree
  std::vector<int> deferred_index; // per column: index among top_columns, or -1
  // Workspace.
  std::vector<double> permuted_storage, scratch_storage[2], deferred_storage[2];
  double* permuted = nullptr;   // n x 4, 32-byte aligned
  double* scratch[2] = {nullptr, nullptr};   // max_rows x 4 per thread
  double* deferred[2] = {nullptr, nullptr};  // top_columns x 4 per thread, kept zero between solves

  Impl() {
    cholmod_start(&common);
    common.print = 0;                // libraries never print
    common.error_handler = nullptr;
    common.supernodal = CHOLMOD_SUPERNODAL;
    common.final_ll = 1;
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
    permutation.clear();
    view = {};
    parallel = false;
    for (auto& range : ranges) range.clear();
    top.clear();
    top_columns.clear();
    direct_rows.clear();
    deferred_index.clear();
  }

  void BuildView();
  void BuildDiagonal();
  void BuildSchedule();
  template <int R>
  void SolvePermuted(double* y);
  void SolveRows(double* data, int k, int stride, int first);
};

// The inverse diagonal and, with single precision, the rounded values.
void SparseCholesky::Impl::BuildDiagonal() {
  float_values.clear();
  float_values.shrink_to_fit();
  view.float_values = nullptr;
  if (single_precision) {
    float_values.assign(view.values, view.values + view.value_start[view.count]);
    view.float_values = float_values.data();
  }
  inverse_diagonal.resize(n);
  for (int s = 0; s < view.count; ++s) {
    const int num_rows = view.row_start[s + 1] - view.row_start[s];
    for (int j = 0; j < view.first_col[s + 1] - view.first_col[s]; ++j) {
      const std::size_t at = view.value_start[s] + static_cast<std::size_t>(j) * num_rows + j;
      inverse_diagonal[view.first_col[s] + j] =
          1.0 / (single_precision ? static_cast<double>(float_values[at]) : view.values[at]);
    }
  }
  view.inverse_diagonal = inverse_diagonal.data();
}

void SparseCholesky::Impl::BuildView() {
  view.count = static_cast<int>(factor->nsuper);
  view.first_col = static_cast<const int*>(factor->super);
  view.row_start = static_cast<const int*>(factor->pi);
  view.value_start = static_cast<const int*>(factor->px);
  view.rows = static_cast<const int*>(factor->s);
  view.values = static_cast<const double*>(factor->x);
  BuildDiagonal();
  max_rows = 0;
  for (int s = 0; s < view.count; ++s) max_rows = std::max(max_rows, view.row_start[s + 1] - view.row_start[s]);
  direct_rows.resize(view.count);
  for (int s = 0; s < view.count; ++s) direct_rows[s] = view.row_start[s + 1] - view.row_start[s];
  BuildSchedule();
  permuted = Aligned(&permuted_storage, static_cast<std::size_t>(n) * 4);
  for (int t = 0; t < 2; ++t) scratch[t] = Aligned(&scratch_storage[t], static_cast<std::size_t>(max_rows) * 4);
}

void SparseCholesky::Impl::BuildSchedule() {
  const int count = view.count;
  // Supernodal elimination tree: the parent owns the first row below the supernode.
  std::vector<int> super_of_col(n);
  for (int s = 0; s < count; ++s)
    for (int c = view.first_col[s]; c < view.first_col[s + 1]; ++c) super_of_col[c] = s;
  std::vector<int> parent(count, -1), first(count), size(count, 1);
  std::vector<double> own(count), work(count);
  std::vector<std::vector<int>> children(count);
  double total = 0;
  for (int s = 0; s < count; ++s) {
    const int num_cols = view.first_col[s + 1] - view.first_col[s];
    const int num_rows = view.row_start[s + 1] - view.row_start[s];
    if (num_rows > num_cols) parent[s] = super_of_col[view.rows[view.row_start[s] + num_cols]];
    if (parent[s] >= 0 && parent[s] <= s) return;  // not a postordered tree: stay serial
    own[s] = work[s] = static_cast<double>(num_cols) * num_rows + num_rows;
    total += own[s];
    first[s] = s;
  }
  if (threads < 2 || total < kMinParallelEntries) return;
  for (int s = 0; s < count; ++s)
    if (parent[s] >= 0) {
      first[parent[s]] = std::min(first[parent[s]], first[s]);
      size[parent[s]] += size[s];
      work[parent[s]] += work[s];
      children[parent[s]].push_back(s);
    }
  for (int s = 0; s < count; ++s)
    if (size[s] != s - first[s] + 1) return;  // subtrees are not contiguous: stay serial

  // Move the heaviest subtree's root to the serial top until the two threads' loads (longest
  // processing time first) plus the serial part stop improving.
  std::vector<int> frontier, top_set;
  for (int s = 0; s < count; ++s)
    if (parent[s] < 0) frontier.push_back(s);
  double top_work = 0, best_cost = total;
  std::vector<int> best_frontier, best_top;
  for (int step = 0; step < 4096 && !frontier.empty(); ++step) {
    std::sort(frontier.begin(), frontier.end(), [&](int a, int b) { return work[a] > work[b]; });
    double bins[2] = {0, 0};
    for (int s : frontier) bins[bins[0] <= bins[1] ? 0 : 1] += work[s];
    const double cost = std::max(bins[0], bins[1]) + top_work;
    if (cost < best_cost) {
      best_cost = cost;
      best_frontier = frontier;
      best_top = top_set;
    }
    const int heaviest = frontier.front();
    if (children[heaviest].empty() || top_work > 0.25 * total) break;
    frontier.erase(frontier.begin());
    top_set.push_back(heaviest);
    top_work += own[heaviest];
    frontier.insert(frontier.end(), children[heaviest].begin(), children[heaviest].end());
  }
  if (best_cost > 0.8 * total || best_frontier.empty()) return;

  double bins[2] = {0, 0};
  for (int s : best_frontier) {
    const int t = bins[0] <= bins[1] ? 0 : 1;
    bins[t] += work[s];
    ranges[t].emplace_back(first[s], s + 1);
    // Rows above the subtree root's last column belong to top supernodes.
    const int last_col = view.first_col[s + 1] - 1;
    for (int d = first[s]; d <= s; ++d) {
      const int* begin = view.rows + view.row_start[d];
      const int* end = view.rows + view.row_start[d + 1];
      direct_rows[d] = static_cast<int>(std::upper_bound(begin, end, last_col) - begin);
    }
  }
  top = best_top;
  std::sort(top.begin(), top.end());
  deferred_index.assign(n, -1);
  for (int s : top)
    for (int c = view.first_col[s]; c < view.first_col[s + 1]; ++c) {
      deferred_index[c] = static_cast<int>(top_columns.size());
      top_columns.push_back(c);
    }
  for (int t = 0; t < 2; ++t) {
    deferred_storage[t].clear();
    deferred[t] = Aligned(&deferred_storage[t], top_columns.size() * 4);
  }
  parallel = true;
}

template <int R>
void SparseCholesky::Impl::SolvePermuted(double* y) {
  const int count = view.count;
  if (!parallel) {
    for (int s = 0; s < count; ++s)
      ForwardSupernode<R>(view, s, y, scratch[0], direct_rows[s], nullptr, nullptr);
    for (int s = count - 1; s >= 0; --s) BackwardSupernode<R>(view, s, y, scratch[0]);
    return;
  }
  auto forward = [&](int t) {
    for (const auto& [begin, end] : ranges[t])
      for (int s = begin; s < end; ++s)
        ForwardSupernode<R>(view, s, y, scratch[t], direct_rows[s], deferred[t],
                            deferred_index.data());
  };
  auto backward = [&](int t) {
    for (auto range = ranges[t].rbegin(); range != ranges[t].rend(); ++range)
      for (int s = range->second - 1; s >= range->first; --s) BackwardSupernode<R>(view, s, y, scratch[t]);
  };
  helper.Run(forward);
  for (std::size_t i = 0; i < top_columns.size(); ++i)
    for (int r = 0; r < R; ++r) {
      y[static_cast<std::size_t>(top_columns[i]) * R + r] -= deferred[0][i * R + r] + deferred[1][i * R + r];
      deferred[0][i * R + r] = deferred[1][i * R + r] = 0.0;
    }
  for (int s : top) ForwardSupernode<R>(view, s, y, scratch[0], direct_rows[s], nullptr, nullptr);
  for (auto s = top.rbegin(); s != top.rend(); ++s) BackwardSupernode<R>(view, *s, y, scratch[0]);
  helper.Run(backward);
}

// Solves for columns [first, first + k) (k <= 4) of a row-major n x stride block, in place.
void SparseCholesky::Impl::SolveRows(double* data, int k, int stride, int first) {
  const int* perm = static_cast<const int*>(factor->Perm);
  double* y = permuted;
  const int width = k == 3 ? 4 : k;  // 3 columns are padded to 4 (one vector register with AVX2)
  for (int i = 0; i < n; ++i) {
    const double* from = data + static_cast<std::size_t>(perm[i]) * stride + first;
    double* to = y + static_cast<std::size_t>(i) * width;
    for (int r = 0; r < k; ++r) to[r] = from[r];
    for (int r = k; r < width; ++r) to[r] = 0.0;
  }
  switch (width) {
    case 1: SolvePermuted<1>(y); break;
    case 2: SolvePermuted<2>(y); break;
    default: SolvePermuted<4>(y); break;
  }
  for (int i = 0; i < n; ++i) {
    const double* from = y + static_cast<std::size_t>(i) * width;
    double* to = data + static_cast<std::size_t>(perm[i]) * stride + first;
    for (int r = 0; r < k; ++r) to[r] = from[r];
  }
}

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
  s.n = n;
  s.permutation.resize(n);
  for (int i = 0; i < n; ++i) s.permutation[i] = i;
  if (s.factor->is_super && s.factor->xtype == CHOLMOD_REAL && s.factor->itype == CHOLMOD_INT)
    std::memcpy(s.permutation.data(), s.factor->Perm, sizeof(int) * n);
  // The supernodal factor is solved by the kernels above: CHOLMOD's own supernodal solve makes
  // one BLAS call per supernode, which dominates for the few right-hand sides of a frame.
  if (s.factor->is_super && s.factor->xtype == CHOLMOD_REAL && s.factor->itype == CHOLMOD_INT) s.BuildView();
  return CholeskyStatus::kOk;
}

void SparseCholesky::SolveRowMajor(double* data, int k) const {
  Impl& s = *impl_;
  if (s.factor == nullptr || k < 1) std::abort();
  if (s.view.count > 0) {
    for (int first = 0; first < k; first += 4) s.SolveRows(data, std::min(4, k - first), k, first);
    return;
  }
  Eigen::MatrixXd columns(s.n, k);
  for (int i = 0; i < s.n; ++i)
    for (int r = 0; r < k; ++r) columns(i, r) = data[static_cast<std::size_t>(i) * k + r];
  const Eigen::MatrixXd solved = Solve(columns);
  for (int i = 0; i < s.n; ++i)
    for (int r = 0; r < k; ++r) data[static_cast<std::size_t>(i) * k + r] = solved(i, r);
}

void SparseCholesky::SolvePermuted4(double* data) const {
  Impl& s = *impl_;
  if (s.factor == nullptr) std::abort();
  if (s.view.count == 0) {  // the ordering is the identity here
    SolveRowMajor(data, 4);
    return;
  }
  if (reinterpret_cast<std::uintptr_t>(data) % 32 == 0) {
    s.SolvePermuted<4>(data);
    return;
  }
  const std::size_t size = static_cast<std::size_t>(s.n) * 4;
  std::copy(data, data + size, s.permuted);
  s.SolvePermuted<4>(s.permuted);
  std::copy(s.permuted, s.permuted + size, data);
}

const std::vector<int>& SparseCholesky::permutation() const { return impl_->permutation; }

Eigen::MatrixXd SparseCholesky::Solve(const Eigen::MatrixXd& rhs) const {
  Impl& s = *impl_;
  if (s.factor == nullptr || rhs.rows() != s.n) std::abort();
  const int k = static_cast<int>(rhs.cols());
  if (k == 0) return Eigen::MatrixXd(s.n, 0);
  if (s.view.count > 0) {
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows = rhs;
    for (int first = 0; first < k; first += 4) s.SolveRows(rows.data(), std::min(4, k - first), k, first);
    return rows;
  }
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

void SparseCholesky::set_single_precision(bool single) {
  Impl& s = *impl_;
  if (s.single_precision == single) return;
  s.single_precision = single;
  if (s.view.count > 0) s.BuildDiagonal();
}

void SparseCholesky::set_threads(int threads) {
  Impl& s = *impl_;
  s.threads = std::max(1, threads);
  if (s.view.count > 0) {
    // Rebuild the schedule for the new thread count.
    s.parallel = false;
    for (auto& range : s.ranges) range.clear();
    s.top.clear();
    s.top_columns.clear();
    s.deferred_index.clear();
    for (int d = 0; d < s.view.count; ++d) s.direct_rows[d] = s.view.row_start[d + 1] - s.view.row_start[d];
    s.BuildSchedule();
  }
}

bool SparseCholesky::is_factored() const { return impl_ && impl_->factor != nullptr; }
int SparseCholesky::rows() const { return impl_ ? impl_->n : 0; }
double SparseCholesky::factor_nonzeros() const {
  if (!is_factored()) return 0.0;
  return impl_->common.lnz;
}
const std::string& SparseCholesky::message() const { return impl_->message; }

}  // namespace confluent
