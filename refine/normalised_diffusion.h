#pragma once
// Normalised diffusion of sparse per-vertex values over a mesh: values known at some vertices
// (rim steps, photo-consistency offsets) become a smooth field that fades out far from them.
// D = S(w v) / (S(w) + fade), with S = gamma (L + gamma I)^-1, L the cotangent Laplacian and
// gamma = stiffness x mean diagonal of L; the sparse factor is computed once per mesh.

#include <Eigen/Core>
#include <memory>
#include <string>

#include "core/mesh.h"

namespace confluent {

class NormalisedDiffusion {
 public:
  // `mesh` gives the topology and the geometry of the Laplacian. A value spreads over about
  // 1 / sqrt(stiffness) edges. Throws InputError(source, ...) when the system cannot be
  // factored (e.g. a mesh without faces); aborts on stiffness <= 0.
  NormalisedDiffusion(const Mesh& mesh, double stiffness, const std::string& source = "mesh");
  ~NormalisedDiffusion();
  NormalisedDiffusion(NormalisedDiffusion&&) noexcept;
  NormalisedDiffusion& operator=(NormalisedDiffusion&&) noexcept;

  // `values` (n x k) are read where `known` (n) is true. Returns the spread field (n x k); rows
  // far from every known vertex tend to 0 (the larger `fade`, the faster). Non-finite results
  // (none expected) are returned as 0.
  Eigen::MatrixXd Spread(const Eigen::MatrixXd& values, const std::vector<bool>& known, double fade) const;

  int num_vertices() const;
  void set_threads(int threads);  // threads of the triangular solves (default 1)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace confluent
