// Normalised diffusion over a mesh (refine/normalised_diffusion.h).

#include <gtest/gtest.h>

#include "core/error.h"
#include "core/mesh_ops.h"
#include "refine/normalised_diffusion.h"

namespace confluent {
namespace {

TEST(NormalisedDiffusion, AValueKnownEverywhereComesBackScaledByTheFade) {
  const Mesh sphere = MakeUvSphere(0.3, 12, 24);
  const NormalisedDiffusion diffusion(sphere, 0.01);
  const int n = sphere.num_vertices();
  Eigen::MatrixXd values(n, 2);
  values.col(0).setConstant(2.0);
  values.col(1).setConstant(-0.5);
  const Eigen::MatrixXd spread = diffusion.Spread(values, std::vector<bool>(n, true), 0.25);
  // The Laplacian annihilates constants, so S(1) = 1 and D = v / (1 + fade).
  EXPECT_NEAR(spread.col(0).minCoeff(), 1.6, 1e-9);
  EXPECT_NEAR(spread.col(0).maxCoeff(), 1.6, 1e-9);
  EXPECT_NEAR(spread.col(1).mean(), -0.4, 1e-9);
}

TEST(NormalisedDiffusion, OneKnownVertexFadesWithDistance) {
  const Mesh sphere = MakeUvSphere(0.3, 24, 48);
  const NormalisedDiffusion diffusion(sphere, 0.01);
  const int n = sphere.num_vertices();
  int top = 0;
  sphere.vertices.col(2).maxCoeff(&top);
  std::vector<bool> known(n, false);
  known[top] = true;
  Eigen::MatrixXd values = Eigen::MatrixXd::Zero(n, 1);
  values(top, 0) = 1.0;
  const Eigen::MatrixXd spread = diffusion.Spread(values, known, 0.05);
  int bottom = 0;
  sphere.vertices.col(2).minCoeff(&bottom);
  // A lone known vertex has little diffused weight, so the fade shows even there.
  EXPECT_DOUBLE_EQ(spread.maxCoeff(), spread(top, 0));
  EXPECT_GT(spread(top, 0), 0.2);
  EXPECT_LT(spread(top, 0), 1.0);
  EXPECT_LT(spread(bottom, 0), 0.01 * spread(top, 0));
  // Monotone along a meridian: nearer the known vertex, larger.
  double previous = 2.0;
  for (double z : {0.25, 0.1, -0.1, -0.25}) {
    int nearest = 0;
    (sphere.vertices.col(2).array() - z).abs().minCoeff(&nearest);
    EXPECT_LT(spread(nearest, 0), previous) << z;
    previous = spread(nearest, 0);
  }
  EXPECT_THROW(diffusion.Spread(values.topRows(3), known, 0.05), std::invalid_argument);
}

TEST(NormalisedDiffusion, AMeshWithoutFacesIsNamed) {
  Mesh points;
  points.vertices = RowMatrixX3d::Random(5, 3);
  try {
    NormalisedDiffusion diffusion(points, 0.01, "cloud.ply");
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("cloud.ply"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace confluent
