#include "refine/normalised_diffusion.h"

#include <Eigen/SparseCore>
#include <stdexcept>

#include "core/error.h"
#include "deform/cholmod_solver.h"
#include "deform/laplacian.h"

namespace confluent {

struct NormalisedDiffusion::Impl {
  double gamma = 0.0;
  SparseCholesky factor;  // L + gamma I
};

NormalisedDiffusion::NormalisedDiffusion(const Mesh& mesh, double stiffness, const std::string& source)
    : impl_(std::make_unique<Impl>()) {
  RequireOption(stiffness > 0.0, "NormalisedDiffusion stiffness", stiffness, "> 0");
  if (mesh.num_faces() == 0) throw InputError(source, "diffusion over the surface: the mesh has no faces");
  const Eigen::SparseMatrix<double> laplacian = CotanLaplacian(mesh.vertices, mesh.faces);
  impl_->gamma = stiffness * laplacian.diagonal().mean();
  Eigen::SparseMatrix<double> identity(laplacian.rows(), laplacian.cols());
  identity.setIdentity();
  if (impl_->factor.Factor(laplacian + impl_->gamma * identity) != CholeskyStatus::kOk)
    throw InputError(source, "diffusion over the surface: the system cannot be factored: " + impl_->factor.message());
}

NormalisedDiffusion::~NormalisedDiffusion() = default;
NormalisedDiffusion::NormalisedDiffusion(NormalisedDiffusion&&) noexcept = default;
NormalisedDiffusion& NormalisedDiffusion::operator=(NormalisedDiffusion&&) noexcept = default;

int NormalisedDiffusion::num_vertices() const { return impl_->factor.rows(); }

void NormalisedDiffusion::set_threads(int threads) { impl_->factor.set_threads(threads); }

Eigen::MatrixXd NormalisedDiffusion::Spread(const Eigen::MatrixXd& values, const std::vector<bool>& known,
                                            double fade) const {
  const int n = num_vertices(), k = static_cast<int>(values.cols());
  if (values.rows() != n || static_cast<int>(known.size()) != n)
    throw std::invalid_argument("NormalisedDiffusion::Spread: one row per vertex is needed");
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, k + 1);
  for (int v = 0; v < n; ++v)
    if (known[v]) {
      rhs.row(v).head(k) = impl_->gamma * values.row(v);
      rhs(v, k) = impl_->gamma;
    }
  const Eigen::MatrixXd spread = impl_->factor.Solve(rhs);
  Eigen::MatrixXd field(n, k);
  for (int v = 0; v < n; ++v) {
    const Eigen::RowVectorXd value = spread.row(v).head(k) / (spread(v, k) + fade);
    field.row(v) = value.allFinite() ? value : Eigen::RowVectorXd::Zero(k);
  }
  return field;
}

}  // namespace confluent
