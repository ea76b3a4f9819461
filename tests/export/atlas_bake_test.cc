#include "export/atlas_bake.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "core/error.h"
#include "core/image_metrics.h"
#include "render/renderer.h"
#include "tests/render/renderer_test_util.h"

namespace confluent {
namespace {

constexpr double kPi = 3.14159265358979323846;
const Eigen::Vector3d kCentre(0.0, 0.0, 1.0);

// A sphere whose vertex colours vary smoothly with position: the actor whose appearance is known.
Mesh ColouredSphere() {
  Mesh mesh = render_test::MakeIcosphere(kCentre, 0.5, 4);
  const Eigen::ArrayXXd p = (mesh.vertices.rowwise() - kCentre.transpose()).array() * 5.0;
  Eigen::ArrayXXd colours(p.rows(), 3);
  colours << p.col(0).sin(), (p.col(1) + 1.0).sin(), p.col(2).cos();
  mesh.colors = (0.5 + 0.4 * colours).matrix().cast<float>();
  return mesh;
}

Camera RingCamera(const std::string& name, double azimuth_deg, double height_m, int width = 320, int height = 240) {
  const double a = azimuth_deg * kPi / 180.0;
  return LookAtCamera(name, Eigen::Vector3d(3.0 * std::cos(a), 3.0 * std::sin(a), height_m), kCentre, width, height,
                      340.0 * width / 320.0);
}

// Unlit renders: `encoded` false gives the albedo bytes as stored (vertex colours x 255); true
// encodes with sRGB, which gives an 8-bit texture back as stored (GL decodes it when sampling).
RenderResult Draw(MeshRenderer& renderer, int handle, const Camera& camera, bool encoded) {
  RenderRequest request;
  request.silhouette = true;
  request.meshes = {handle};
  request.shading.lit = false;
  request.shading.srgb_output = encoded;
  return renderer.Render(camera, request);
}

// Atlas texels whose centre lies inside a UV triangle (top image row = v = 1), rasterised here.
std::vector<std::uint8_t> Coverage(const UvAtlas& atlas) {
  const int size = atlas.size_px;
  std::vector<std::uint8_t> covered(static_cast<std::size_t>(size) * size, 0);
  for (int f = 0; f < atlas.face_uvs.rows(); ++f) {
    Eigen::Vector2d p[3];
    for (int k = 0; k < 3; ++k) p[k] = atlas.uvs.row(atlas.face_uvs(f, k)).transpose() * size;
    const double area2 = (p[1] - p[0]).x() * (p[2] - p[0]).y() - (p[1] - p[0]).y() * (p[2] - p[0]).x();
    const Eigen::Vector2d lo = p[0].cwiseMin(p[1]).cwiseMin(p[2]), hi = p[0].cwiseMax(p[1]).cwiseMax(p[2]);
    for (int y = std::max(0, static_cast<int>(lo.y()) - 1); y < std::min(size, static_cast<int>(hi.y()) + 1); ++y)
      for (int x = std::max(0, static_cast<int>(lo.x()) - 1); x < std::min(size, static_cast<int>(hi.x()) + 1); ++x) {
        const Eigen::Vector2d q(x + 0.5, y + 0.5);
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
          const Eigen::Vector2d a = p[(k + 1) % 3], b = p[(k + 2) % 3];
          inside = ((b - a).x() * (q - a).y() - (b - a).y() * (q - a).x()) / area2 >= 0;
        }
        if (inside) covered[static_cast<std::size_t>(size - 1 - y) * size + x] = 1;
      }
  }
  return covered;
}

struct Scene {
  Mesh mesh = ColouredSphere();
  UvAtlas atlas;
  std::vector<Camera> cameras;
  std::vector<Image> images;
  MeshRenderer renderer;
  int direct = 0;
  explicit Scene(int atlas_px) {
    UvAtlasOptions options;
    options.size_px = atlas_px;
    atlas = BuildUvAtlas(mesh, options);
    direct = renderer.AddMesh(mesh, "sphere");
  }
  // One input camera that sees nothing of the sphere (looking away), with a black image.
  void AwayInput() {
    cameras = {LookAtCamera("away", Eigen::Vector3d(0, -3, 1.0), Eigen::Vector3d(0, -6, 1.0), 160, 120, 170)};
    images = {Image(160, 120, 3)};
  }
  // Input cameras: a ring of 6, alternately low and high, so that every part is seen.
  void RingInputs() {
    for (int i = 0; i < 6; ++i) {
      cameras.push_back(RingCamera("in" + std::to_string(i), 60.0 * i, i % 2 ? 2.2 : 0.2));
      images.push_back(Draw(renderer, direct, cameras.back(), false).color);
    }
  }
  // PSNR (inside the union of the silhouettes) of the atlas-textured sphere against the
  // vertex-coloured one in `view`.
  double AtlasPsnr(const Image& baked, const Camera& view) {
    const int textured = renderer.AddMesh(WithAtlasUvs(mesh, atlas), "atlas sphere", baked);
    const RenderResult a = Draw(renderer, textured, view, true), b = Draw(renderer, direct, view, false);
    return MaskedPsnr(a.color, b.color, UnionMask(a.silhouette, b.silhouette));
  }
};

TEST(AtlasBake, BakedAtlasRendersLikeTheSurface) {
  Scene scene(512);
  scene.RingInputs();
  AtlasBaker baker(scene.mesh, scene.atlas);
  const Image baked = baker.Bake(scene.mesh.vertices, scene.cameras, scene.images);
  ASSERT_EQ(baked.width, 512);
  ASSERT_EQ(baked.height, 512);
  ASSERT_EQ(baked.channels, 3);
  // Views the inputs did not have: between two cameras, above, and closer.
  for (const Camera& view : {RingCamera("between", 30.0, 1.2), RingCamera("other", 200.0, 1.6),
                             LookAtCamera("close", Eigen::Vector3d(1.2, -1.0, 1.5), kCentre, 320, 240, 340)}) {
    const double psnr = scene.AtlasPsnr(baked, view);
    std::printf("%s: atlas-textured vs surface PSNR %.2f dB\n", view.name.c_str(), psnr);
    // Two resamplings (input image -> atlas texel -> view pixel) of smooth colours, and the
    // blending of several cameras; 38 dB is an RMS error of 1.3% (measured: 44.3, 44.5, 48.6 dB).
    EXPECT_GE(psnr, 38.0) << view.name;
  }
}

TEST(AtlasBake, AgreesWithRendersProjectiveTexturing) {
  // The same cameras through ProjectiveTexturer::Render (the native path of `render`) and through
  // the baked atlas: the same visibility and blending, up to the view direction (the bake's viewer
  // is along the normal) and the atlas's resampling.
  Scene scene(512);
  scene.RingInputs();
  AtlasBaker baker(scene.mesh, scene.atlas);
  const Image baked = baker.Bake(scene.mesh.vertices, scene.cameras, scene.images);
  ProjectiveTexturer texturer(scene.mesh);
  texturer.SetFrame(scene.mesh.vertices, scene.cameras, scene.images);
  const Camera view = RingCamera("between", 100.0, 1.5);
  const RenderResult native = texturer.Render(view, true);
  const int textured = scene.renderer.AddMesh(WithAtlasUvs(scene.mesh, scene.atlas), "atlas sphere", baked);
  const RenderResult atlas = Draw(scene.renderer, textured, view, true);
  const double psnr = MaskedPsnr(atlas.color, native.color, UnionMask(atlas.silhouette, native.silhouette));
  std::printf("atlas vs projective texturing: %.2f dB\n", psnr);  // measured 42.4 dB
  EXPECT_GE(psnr, 38.0);
}

TEST(AtlasBake, UnseenSurfaceTakesTheVertexColours) {
  Scene scene(512);
  // One camera that sees nothing of the sphere: every texel falls back to the vertex colours.
  scene.AwayInput();
  AtlasBaker baker(scene.mesh, scene.atlas);
  const Image baked = baker.Bake(scene.mesh.vertices, scene.cameras, scene.images);
  const double psnr = scene.AtlasPsnr(baked, RingCamera("view", 45.0, 1.3));
  std::printf("vertex colours through the atlas: %.2f dB\n", psnr);
  EXPECT_GE(psnr, 38.0);  // one resampling of interpolated vertex colours (measured 43.7 dB)
  // And a camera that sees the surface changes it: a grey image gives grey where it sees.
  scene.cameras = {RingCamera("grey", 0.0, 1.0)};
  scene.images = {Image(320, 240, 3)};
  std::fill(scene.images[0].data.begin(), scene.images[0].data.end(), 128);
  const Image grey = baker.Bake(scene.mesh.vertices, scene.cameras, scene.images);
  const std::vector<std::uint8_t> covered = Coverage(scene.atlas);
  int grey_texels = 0, chart_texels = 0;
  for (std::size_t i = 0; i < covered.size(); ++i) {
    if (!covered[i]) continue;
    ++chart_texels;
    grey_texels += grey.data[3 * i] == 128 && grey.data[3 * i + 1] == 128 && grey.data[3 * i + 2] == 128;
  }
  // About a third of the sphere faces the camera well enough (grazing ramp, feathering).
  EXPECT_GT(grey_texels, chart_texels / 6);
  EXPECT_LT(grey_texels, chart_texels / 2);
}

TEST(AtlasBake, GuttersAreFilledFromTheCharts) {
  Scene scene(256);
  scene.AwayInput();
  AtlasBaker baker(scene.mesh, scene.atlas);
  const Image baked = baker.Bake(scene.mesh.vertices, scene.cameras, scene.images);
  const std::vector<std::uint8_t> covered = Coverage(scene.atlas);
  const int size = scene.atlas.size_px;
  // Every texel next to a chart (outside it) has about the colour of its chart neighbours.
  int checked = 0, wrong = 0;
  for (int y = 1; y + 1 < size; ++y)
    for (int x = 1; x + 1 < size; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * size + x;
      if (covered[i]) continue;
      for (const int d : {-1, 1, -size, size}) {
        if (!covered[i + d]) continue;
        ++checked;
        int difference = 0;
        for (int c = 0; c < 3; ++c) difference = std::max(difference, std::abs(baked.data[3 * i + c] - baked.data[3 * (i + d) + c]));
        wrong += difference > 24;
        break;
      }
    }
  EXPECT_GT(checked, 500);
  EXPECT_LE(wrong, checked / 100);
}

TEST(AtlasBake, BadInputThrows) {
  Scene scene(128);
  Mesh other = render_test::MakeIcosphere(kCentre, 0.5, 2);
  EXPECT_THROW(AtlasBaker(other, scene.atlas), InputError);
  AtlasBaker baker(scene.mesh, scene.atlas);
  EXPECT_THROW(baker.Rebake({}), UsageError);
  EXPECT_THROW(baker.Bake(other.vertices, {RingCamera("c", 0, 1)}, {Image(320, 240, 3)}), InputError);
}

}  // namespace
}  // namespace confluent
