#include "export/uv_atlas.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "core/error.h"
#include "studio/actor.h"
#include "tests/render/renderer_test_util.h"

namespace confluent {
namespace {

// What every atlas must be: UVs in [0, 1] for every face corner, no flipped triangle, and no
// texel centre of the atlas inside two triangles (rasterised at the atlas's resolution, samples
// strictly inside). Returns the fraction of texels covered.
double CheckAtlas(const Mesh& mesh, const UvAtlas& atlas) {
  EXPECT_EQ(atlas.face_uvs.rows(), mesh.num_faces());
  EXPECT_GT(atlas.size_px, 0);
  const int size = atlas.size_px;
  EXPECT_GE(atlas.uvs.minCoeff(), 0.0);
  EXPECT_LE(atlas.uvs.maxCoeff(), 1.0);
  EXPECT_GE(atlas.face_uvs.minCoeff(), 0);
  EXPECT_LT(atlas.face_uvs.maxCoeff(), atlas.uvs.rows());
  std::vector<std::uint8_t> hits(static_cast<std::size_t>(size) * size, 0);
  int flipped = 0, overlapping = 0;
  std::size_t covered = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) p[k] = atlas.uvs.row(atlas.face_uvs(f, k)).transpose() * size;
    const double area2 = (p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x();
    if (!(area2 > 0)) {
      ++flipped;
      continue;
    }
    // Texel (x, y) has its centre at (x + 0.5, y + 0.5) in these units.
    const int x0 = std::max(0, static_cast<int>(std::min({p[0].x(), p[1].x(), p[2].x()})) - 1);
    const int x1 = std::min(size - 1, static_cast<int>(std::max({p[0].x(), p[1].x(), p[2].x()})) + 1);
    const int y0 = std::max(0, static_cast<int>(std::min({p[0].y(), p[1].y(), p[2].y()})) - 1);
    const int y1 = std::min(size - 1, static_cast<int>(std::max({p[0].y(), p[1].y(), p[2].y()})) + 1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const Eigen::Vector2d q(x + 0.5, y + 0.5);
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
          const Eigen::Vector2d a = p[(k + 1) % 3], b = p[(k + 2) % 3];
          inside = (b - a).x() * (q - a).y() - (b - a).y() * (q - a).x() > 1e-9 * area2;
        }
        if (!inside) continue;
        std::uint8_t& hit = hits[static_cast<std::size_t>(y) * size + x];
        overlapping += hit == 1;
        covered += hit == 0;
        hit = 1;
      }
  }
  EXPECT_EQ(flipped, 0);
  EXPECT_EQ(overlapping, 0);
  const double use = static_cast<double>(covered) / (static_cast<double>(size) * size);
  EXPECT_NEAR(use, atlas.stats.texel_use, 1e-3);
  return use;
}

// Builds the atlas of `mesh` at `size_px`, checks it (CheckAtlas) and prints its figures.
UvAtlas CheckedAtlas(const Mesh& mesh, int size_px, const char* what, int padding_px = 4) {
  UvAtlasOptions options;
  options.size_px = size_px;
  options.padding_px = padding_px;
  const UvAtlas atlas = BuildUvAtlas(mesh, options);
  const double use = CheckAtlas(mesh, atlas);
  std::printf("%s, %d faces: %d charts, texel use %.3f, stretch mean %.3f max %.3f\n", what, mesh.num_faces(),
              atlas.stats.charts, use, atlas.stats.stretch_mean, atlas.stats.stretch_max);
  return atlas;
}

Mesh StudioMesh() {
  StudioActorOptions options;
  options.target_triangles = 12000;
  return BuildStudioActor(options).mesh;
}

TEST(UvAtlas, StudioActorWithSegmentLabels) {
  const Mesh mesh = StudioMesh();
  ASSERT_TRUE(mesh.has_face_labels());
  const UvAtlas atlas = CheckedAtlas(mesh, 1024, "studio actor");
  const double use = atlas.stats.texel_use;
  EXPECT_GE(atlas.stats.charts, 16);  // at least one per body segment
  EXPECT_GT(use, 0.40);  // measured 0.435 (79 charts)
  EXPECT_GE(atlas.stats.stretch_mean, 1.0);
  EXPECT_LT(atlas.stats.stretch_mean, 1.15);
  EXPECT_LT(atlas.stats.stretch_max, 4.0);
}

TEST(UvAtlas, StudioActorWithoutLabels) {
  Mesh mesh = StudioMesh();
  mesh.face_labels.clear();
  const UvAtlas atlas = CheckedAtlas(mesh, 1024, "unlabelled actor");
  const double use = atlas.stats.texel_use;
  EXPECT_GE(atlas.stats.charts, 6);
  EXPECT_GT(use, 0.28);  // measured 0.318 (43 charts, larger and less regular)
  EXPECT_LT(atlas.stats.stretch_mean, 1.15);
  EXPECT_LT(atlas.stats.stretch_max, 4.0);
}

TEST(UvAtlas, SphereIsCutIntoDiscsWithLowStretch) {
  const Mesh sphere = render_test::MakeIcosphere(Eigen::Vector3d(0, 0, 1), 0.5, 4);
  const UvAtlas atlas = CheckedAtlas(sphere, 512, "sphere", 2);
  const double use = atlas.stats.texel_use;
  // A closed sphere cannot be one disc; the six normal directions give about six charts.
  EXPECT_GE(atlas.stats.charts, 6);
  EXPECT_LE(atlas.stats.charts, 40);
  EXPECT_GT(use, 0.36);  // measured 0.402: six round-ish charts in their boxes
  EXPECT_LT(atlas.stats.stretch_mean, 1.1);
}

TEST(UvAtlas, PlanarGridIsOneUndistortedChart) {
  // A flat 20 x 10 grid: one chart, an exact similarity (stretch 1 everywhere).
  Mesh grid;
  const int nx = 21, ny = 11;
  grid.vertices.resize(nx * ny, 3);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) grid.vertices.row(j * nx + i) << 0.05 * i, 0.05 * j + 0.01 * (i % 2), 0.0;
  grid.faces.resize(2 * (nx - 1) * (ny - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i;
      grid.faces.row(f++) << a, a + 1, a + nx + 1;
      grid.faces.row(f++) << a, a + nx + 1, a + nx;
    }
  UvAtlasOptions options;
  options.size_px = 256;
  options.min_chart_faces = 0;
  const UvAtlas atlas = BuildUvAtlas(grid, options);
  CheckAtlas(grid, atlas);
  EXPECT_EQ(atlas.stats.charts, 1);
  EXPECT_NEAR(atlas.stats.stretch_mean, 1.0, 1e-4);
  EXPECT_NEAR(atlas.stats.stretch_max, 1.0, 1e-4);
}

TEST(UvAtlas, BadInputThrows) {
  UvAtlasOptions options;
  options.size_px = 10;
  EXPECT_THROW(options.Check(), UsageError);
  options = {};
  options.max_chart_stretch = 0.5;
  EXPECT_THROW(options.Check(), UsageError);
  EXPECT_THROW(BuildUvAtlas(Mesh()), InputError);
  Mesh bad = render_test::MakeIcosphere(Eigen::Vector3d::Zero(), 1.0, 1);
  bad.faces(0, 0) = bad.num_vertices();
  EXPECT_THROW(BuildUvAtlas(bad), InputError);
}

}  // namespace
}  // namespace confluent
