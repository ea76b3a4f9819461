#include "render/projective_texture.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/image_metrics.h"
#include "render/renderer.h"
#include "tests/render/renderer_test_util.h"

namespace confluent {
namespace {

const Eigen::Vector3d kCentre(0.0, 0.0, 1.0);

// A sphere with smoothly varying vertex colours (the "real" actor).
Mesh ColouredSphere() {
  Mesh mesh = render_test::MakeIcosphere(kCentre, 0.5, 4);
  mesh.colors.resize(mesh.num_vertices(), 3);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = mesh.vertices.row(v).transpose() - kCentre;
    mesh.colors(v, 0) = static_cast<float>(0.5 + 0.35 * std::sin(6.0 * p.x()));
    mesh.colors(v, 1) = static_cast<float>(0.5 + 0.35 * std::sin(6.0 * p.y() + 1.0));
    mesh.colors(v, 2) = static_cast<float>(0.5 + 0.35 * std::cos(6.0 * p.z()));
  }
  return mesh;
}

// The same geometry with one flat colour (what texturing must not show where cameras see).
Mesh FlatSphere(float r, float g, float b) {
  Mesh mesh = ColouredSphere();
  for (int v = 0; v < mesh.num_vertices(); ++v) mesh.colors.row(v) << r, g, b;
  return mesh;
}

Camera RingCamera(const std::string& name, double azimuth_deg, double height_m, int width = 160, int height = 120) {
  const double a = azimuth_deg * M_PI / 180.0;
  return LookAtCamera(name, Eigen::Vector3d(3.0 * std::cos(a), 3.0 * std::sin(a), height_m), kCentre, width, height,
                      170.0 * width / 160.0);
}

// Unlit, unencoded renders of `mesh` (the ground-truth images of the cameras).
struct GroundTruth {
  MeshRenderer renderer;
  int handle = 0;
  explicit GroundTruth(const Mesh& mesh) { handle = renderer.AddMesh(mesh); }
  RenderResult Render(const Camera& camera) {
    RenderRequest request;
    request.silhouette = true;
    request.shading.lit = false;
    request.shading.srgb_output = false;
    return renderer.Render(camera, request);
  }
};

// A ring of cameras alternately low and high, so that every part of the sphere is seen.
std::vector<Camera> Ring(int count) {
  std::vector<Camera> ring;
  for (int i = 0; i < count; ++i)
    ring.push_back(RingCamera("cam" + std::to_string(i), 360.0 * i / count, i % 2 == 0 ? 2.2 : 0.8));
  return ring;
}

std::vector<Image> ImagesOf(GroundTruth* truth, const std::vector<Camera>& cameras, std::vector<Image>* masks = nullptr) {
  std::vector<Image> images;
  for (const Camera& camera : cameras) {
    RenderResult result = truth->Render(camera);
    images.push_back(result.color);
    if (masks != nullptr) masks->push_back(result.silhouette);
  }
  return images;
}

// The coloured sphere seen by a ring of 8 cameras: the usual input of the texturer.
struct SphereCapture {
  Mesh real = ColouredSphere();
  GroundTruth truth{real};
  std::vector<Camera> ring = Ring(8);
  std::vector<Image> masks;
  std::vector<Image> images = ImagesOf(&truth, ring, &masks);
};

TEST(ProjectiveTexturer, HeldOutViewReproducesTheColours) {
  SphereCapture sphere;
  const Mesh black = FlatSphere(0, 0, 0);  // fallback colours that would ruin the score
  ProjectiveTexturer texturer(black);
  texturer.SetFrame(black.vertices, sphere.ring, sphere.images, sphere.masks);
  for (int visible : texturer.frame_info().visible_pixels) EXPECT_GT(visible, 2000);

  // Held out: between two ring cameras, higher up.
  for (const Camera& heldout : {RingCamera("heldout_a", 22.5, 2.0), RingCamera("heldout_b", 200.0, 0.9)}) {
    const RenderResult expected = sphere.truth.Render(heldout);
    const RenderResult rendered = texturer.Render(heldout, /*want_silhouette=*/true);
    ASSERT_EQ(rendered.color.width, 160);
    ASSERT_EQ(rendered.silhouette.height, 120);
    int differing = 0, covered = 0;
    for (std::size_t p = 0; p < rendered.silhouette.data.size(); ++p) {
      differing += rendered.silhouette.data[p] != expected.silhouette.data[p];
      covered += expected.silhouette.data[p] != 0;
    }
    EXPECT_LE(differing, covered / 100) << "silhouettes must agree (same projection as MeshRenderer)";
    const Image mask = UnionMask(expected.silhouette, rendered.silhouette);
    const double psnr = MaskedPsnr(expected.color, rendered.color, mask);
    EXPECT_GT(psnr, 32.0) << heldout.name;
  }
  // Rendering into an input camera reproduces its image almost exactly.
  const double self = MaskedPsnr(sphere.images[3], texturer.Render(sphere.ring[3]).color, sphere.masks[3]);
  EXPECT_GT(self, 38.0);
}

// A real camera's colour response (SetViewGains): every input colour scaled per channel, so the
// view scales with it; an empty list restores the plain view.
TEST(ProjectiveTexturer, ViewGainsScaleTheBlendedColours) {
  SphereCapture sphere;
  ProjectiveTexturer texturer(sphere.real);
  texturer.SetFrame(sphere.real.vertices, sphere.ring, sphere.images, sphere.masks);
  const Camera view = RingCamera("heldout", 22.5, 1.6);
  const RenderResult plain = texturer.Render(view, true);
  const Eigen::Vector3d gain(1.1, 1.0, 0.8);
  texturer.SetViewGains(std::vector<Eigen::Vector3d>(sphere.ring.size(), gain));
  const RenderResult scaled = texturer.Render(view, true);
  int checked = 0;
  for (std::size_t p = 0; p < plain.silhouette.data.size(); ++p) {
    if (!plain.silhouette.data[p]) continue;
    for (int c = 0; c < 3; ++c) {
      const double expected = std::min(255.0, plain.color.data[3 * p + c] * gain[c]);
      EXPECT_NEAR(scaled.color.data[3 * p + c], expected, 1.5 + 0.01 * expected) << p;
    }
    ++checked;
  }
  EXPECT_GT(checked, 1000);
  texturer.SetViewGains({});
  EXPECT_EQ(texturer.Render(view, true).color.data, plain.color.data);
  EXPECT_THROW(texturer.SetViewGains({gain}), UsageError);
  EXPECT_THROW(texturer.SetViewGains(std::vector<Eigen::Vector3d>(sphere.ring.size(), Eigen::Vector3d(1, NAN, 1))),
               InputError);
}

TEST(ProjectiveTexturer, BlindAndExcludedCamerasContributeNothing) {
  const Mesh real = ColouredSphere();
  GroundTruth truth(real);
  const std::vector<Camera> ring = Ring(6);
  const std::vector<Image> images = ImagesOf(&truth, ring);
  const Mesh grey = FlatSphere(0.5f, 0.5f, 0.5f);
  ProjectiveTexturer texturer(grey);
  texturer.SetFrame(grey.vertices, ring, images);
  const Camera view = RingCamera("view", 45.0, 1.8);
  const Image reference = texturer.Render(view).color;

  // A camera looking away from the actor, with a white image, may not change a single pixel.
  std::vector<Camera> cameras = ring;
  std::vector<Image> with_blind = images;
  cameras.push_back(LookAtCamera("away", Eigen::Vector3d(0, -3, 1.4), Eigen::Vector3d(0, -6, 1.4), 160, 120, 170));
  Image white(160, 120, 3);
  std::fill(white.data.begin(), white.data.end(), 255);
  with_blind.push_back(white);
  texturer.SetFrame(grey.vertices, cameras, with_blind);
  EXPECT_EQ(texturer.frame_info().visible_pixels.back(), 0);
  const Image blind = texturer.Render(view).color;
  EXPECT_EQ(blind.data, reference.data);

  // Excluding a camera (not passing it) changes the result only a little: others fill in.
  std::vector<Camera> five(ring.begin() + 1, ring.end());
  std::vector<Image> five_images(images.begin() + 1, images.end());
  texturer.SetFrame(grey.vertices, five, five_images);
  const RenderResult excluded = texturer.Render(view, true);
  const RenderResult expected = truth.Render(view);
  EXPECT_GT(MaskedPsnr(expected.color, excluded.color, expected.silhouette), 28.0);

  // No cameras at all: the mesh's own colours, nothing else.
  texturer.SetFrame(grey.vertices, {}, {});
  const RenderResult none = texturer.Render(view, true);
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x)
      if (none.silhouette.at<std::uint8_t>(x, y) != 0) {
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(none.color.at<std::uint8_t>(x, y, c), 128, 1);
      }
}

TEST(ProjectiveTexturer, UnseenSurfaceKeepsTheMeshColours) {
  // Green images from cameras on the -y side only; the mesh's own colour is red.
  GroundTruth truth(FlatSphere(0.0f, 1.0f, 0.0f));
  std::vector<Camera> front = {RingCamera("a", -60, 1.2), RingCamera("b", -90, 1.2), RingCamera("c", -120, 1.2)};
  const std::vector<Image> images = ImagesOf(&truth, front);
  const Mesh red = FlatSphere(1.0f, 0.0f, 0.0f);
  ProjectiveTexturer texturer(red);
  texturer.SetFrame(red.vertices, front, images);
  const Image from_front = texturer.Render(RingCamera("front", -90, 1.0)).color;
  const Image from_back = texturer.Render(RingCamera("back", 90, 1.0)).color;
  // Image centre: the sphere's point nearest to the viewer.
  EXPECT_GT(from_front.at<std::uint8_t>(80, 60, 1), 240);
  EXPECT_LT(from_front.at<std::uint8_t>(80, 60, 0), 15);
  EXPECT_GT(from_back.at<std::uint8_t>(80, 60, 0), 240);
  EXPECT_LT(from_back.at<std::uint8_t>(80, 60, 1), 15);
}

TEST(ProjectiveTexturer, ColourBalanceRecoversACameraGain) {
  const Mesh real = ColouredSphere();
  GroundTruth truth(real);
  const std::vector<Camera> ring = Ring(6);
  std::vector<Image> images = ImagesOf(&truth, ring);
  // Camera 2 is 30% darker.
  for (std::uint8_t& value : images[2].data) value = static_cast<std::uint8_t>(std::lround(0.7 * value));
  const Mesh grey = FlatSphere(0.5f, 0.5f, 0.5f);
  ProjectiveTextureOptions options;
  options.colour_balance = true;
  ProjectiveTexturer texturer(grey, options);
  texturer.SetFrame(grey.vertices, ring, images);
  const std::vector<Eigen::Vector3d>& gains = texturer.frame_info().colour_gains;
  ASSERT_EQ(gains.size(), 6u);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(gains[2][c] / gains[0][c], 1.0 / 0.7, 0.05) << c;
    EXPECT_NEAR(gains[4][c] / gains[0][c], 1.0, 0.03) << c;
  }
  // And the balanced render of a view next to camera 2 is better than the unbalanced one.
  const Camera view = RingCamera("view", 130.0, 1.6);
  const RenderResult expected = truth.Render(view);
  const double balanced = MaskedPsnr(expected.color, texturer.Render(view).color, expected.silhouette);
  ProjectiveTexturer plain(grey);
  plain.SetFrame(grey.vertices, ring, images);
  const double unbalanced = MaskedPsnr(expected.color, plain.Render(view).color, expected.silhouette);
  EXPECT_GT(balanced, unbalanced + 1.0);
}

TEST(ProjectiveTexturer, DistortedCamerasOnBothSides) {
  const Mesh real = ColouredSphere();
  GroundTruth truth(real);
  std::vector<Camera> ring = Ring(8);
  for (Camera& camera : ring) camera.dist << -0.2, 0.05, 0.001, -0.001, 0.0;
  std::vector<Image> masks;
  const std::vector<Image> images = ImagesOf(&truth, ring, &masks);
  const Mesh black = FlatSphere(0, 0, 0);
  ProjectiveTexturer texturer(black);
  texturer.SetFrame(black.vertices, ring, images, masks);
  Camera heldout = RingCamera("heldout", 67.5, 1.9);
  heldout.dist << -0.25, 0.08, 0.0, 0.0, 0.0;
  const RenderResult expected = truth.Render(heldout);
  const RenderResult rendered = texturer.Render(heldout, true);
  const Image mask = UnionMask(expected.silhouette, rendered.silhouette);
  EXPECT_GT(MaskedPsnr(expected.color, rendered.color, mask), 28.0);
}

TEST(ProjectiveTexturer, ViewsThatCropTheMeshOrHaveItBehindThem) {
  // The blending pass only runs inside the mesh's projected bounding box; close views crop the
  // box at the image border, and a view with mesh vertices behind it uses the whole image.
  SphereCapture sphere;
  ProjectiveTexturer texturer(sphere.real);
  texturer.SetFrame(sphere.real.vertices, sphere.ring, sphere.images, sphere.masks);
  const Eigen::Vector3d eye = kCentre + Eigen::Vector3d(0.75, 0.0, 0.1);
  for (const Camera& view :
       {LookAtCamera("close", eye, kCentre, 160, 120, 170),
        LookAtCamera("off_centre", eye, kCentre + Eigen::Vector3d(0, 0.6, 0), 160, 120, 170),
        LookAtCamera("sideways", eye, eye + Eigen::Vector3d(-0.4, 1.0, 0.0), 160, 120, 80)}) {
    const RenderResult expected = sphere.truth.Render(view);
    const RenderResult rendered = texturer.Render(view, /*want_silhouette=*/true);
    int differing = 0, covered = 0;
    for (std::size_t p = 0; p < rendered.silhouette.data.size(); ++p) {
      differing += rendered.silhouette.data[p] != expected.silhouette.data[p];
      covered += expected.silhouette.data[p] != 0;
    }
    ASSERT_GT(covered, 500) << view.name;
    EXPECT_LE(differing, covered / 100) << view.name;
    const Image mask = UnionMask(expected.silhouette, rendered.silhouette);
    EXPECT_GT(MaskedPsnr(expected.color, rendered.color, mask), 30.0) << view.name;
  }
}

TEST(ProjectiveTexturer, HalfResolutionVisibilityStaysClose) {
  SphereCapture sphere;
  ProjectiveTextureOptions options;
  options.visibility_scale = 0.5;
  ProjectiveTexturer half(sphere.real, options), full(sphere.real);
  half.SetFrame(sphere.real.vertices, sphere.ring, sphere.images, sphere.masks);
  full.SetFrame(sphere.real.vertices, sphere.ring, sphere.images, sphere.masks);
  // Depth maps at a quarter of the pixels see a quarter of the covered pixels.
  for (std::size_t i = 0; i < sphere.ring.size(); ++i)
    EXPECT_NEAR(half.frame_info().visible_pixels[i], full.frame_info().visible_pixels[i] / 4.0,
                0.05 * full.frame_info().visible_pixels[i] / 4.0);
  const Camera heldout = RingCamera("heldout", 22.5, 2.0);
  const RenderResult expected = sphere.truth.Render(heldout);
  const RenderResult rendered = half.Render(heldout, true);
  const Image mask = UnionMask(expected.silhouette, rendered.silhouette);
  EXPECT_GT(MaskedPsnr(expected.color, rendered.color, mask), 32.0);
  options.visibility_scale = 0.0;
  EXPECT_THROW(options.Check(), UsageError);
  options.visibility_scale = 1.5;
  EXPECT_THROW(options.Check(), UsageError);
}

TEST(ProjectiveTexturer, ProxyDepthMapsFollowTheMeshAndStayClose) {
  Mesh real = ColouredSphere();  // 5120 faces
  std::vector<Camera> ring = Ring(8);
  ring[3].dist << -0.2, 0.05, 0.001, -0.001, 0.0;  // its depth map goes through MeshRenderer
  const Camera heldout = RingCamera("heldout", 22.5, 2.0);
  ProjectiveTextureOptions coarse;
  coarse.visibility_faces = 600;  // depth maps from a ~600-face proxy
  ProjectiveTextureOptions exact;
  exact.visibility_faces = 0;
  ProjectiveTexturer proxy(real, coarse), full(real, exact);
  // The second frame moves and stretches the mesh: the proxy must follow its vertices.
  for (int frame = 0; frame < 2; ++frame) {
    if (frame == 1)
      for (int v = 0; v < real.num_vertices(); ++v)
        real.vertices.row(v) = Eigen::RowVector3d(0.1 + 1.2 * (real.vertices(v, 0) - kCentre.x()),
                                                  real.vertices(v, 1), real.vertices(v, 2));
    GroundTruth truth(real);
    std::vector<Image> masks;
    const std::vector<Image> images = ImagesOf(&truth, ring, &masks);
    proxy.SetFrame(real.vertices, ring, images, masks);
    full.SetFrame(real.vertices, ring, images, masks);
    for (std::size_t i = 0; i < ring.size(); ++i)
      EXPECT_NEAR(proxy.frame_info().visible_pixels[i], full.frame_info().visible_pixels[i],
                  0.05 * full.frame_info().visible_pixels[i])
          << "frame " << frame << " camera " << i;
    const RenderResult expected = truth.Render(heldout);
    const RenderResult from_proxy = proxy.Render(heldout, true);
    const RenderResult from_full = full.Render(heldout, true);
    const Image mask = UnionMask(expected.silhouette, from_proxy.silhouette);
    const double psnr_proxy = MaskedPsnr(expected.color, from_proxy.color, mask);
    // (About 50 dB for both here: the proxy costs nothing visible.)
    EXPECT_GT(psnr_proxy, 40.0) << "frame " << frame;
    EXPECT_GT(psnr_proxy, MaskedPsnr(expected.color, from_full.color, mask) - 2.0) << "frame " << frame;
  }
  coarse.visibility_faces = -1;
  EXPECT_THROW(coarse.Check(), UsageError);
}

TEST(ProjectiveTexturer, CpuAndGlRasterisationAgree) {
  // Raster::kCpu (render/cpu_raster.h, the default on a software GL) and Raster::kGl draw the same
  // depth maps and G-buffer (same coverage rule and depth interpolation): the renders agree up to
  // float rounding, with distorted input cameras and views, cropped views and unseen surface.
  const Mesh real = ColouredSphere();
  GroundTruth truth(real);
  std::vector<Camera> ring = Ring(6);  // the bottom of the sphere stays unseen: the mesh's colour
  ring[1].dist << -0.2, 0.05, 0.001, -0.001, 0.0;
  std::vector<Image> masks;
  const std::vector<Image> images = ImagesOf(&truth, ring, &masks);
  const Mesh grey = FlatSphere(0.2f, 0.6f, 0.3f);
  ProjectiveTextureOptions cpu_options, gl_options;
  cpu_options.raster = ProjectiveTextureOptions::Raster::kCpu;
  gl_options.raster = ProjectiveTextureOptions::Raster::kGl;
  ProjectiveTexturer cpu(grey, cpu_options), gl(grey, gl_options);
  cpu.SetFrame(grey.vertices, ring, images, masks);
  gl.SetFrame(grey.vertices, ring, images, masks);
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const int a = cpu.frame_info().visible_pixels[i], b = gl.frame_info().visible_pixels[i];
    EXPECT_GT(a, 2000);
    EXPECT_NEAR(a, b, b / 500 + 2) << ring[i].name;
  }
  Camera distorted = RingCamera("distorted", 100, 1.6);
  distorted.dist << -0.25, 0.08, 0.0, 0.0, 0.0;
  const Eigen::Vector3d eye = kCentre + Eigen::Vector3d(0.0, -0.8, 0.1);
  for (const Camera& view : {RingCamera("between", 30, 1.4), distorted, LookAtCamera("close", eye, kCentre, 160, 120, 170),
                             LookAtCamera("below", kCentre + Eigen::Vector3d(0.3, 0.1, -2.2), kCentre, 160, 120, 170)}) {
    const RenderResult a = cpu.Render(view, true), b = gl.Render(view, true);
    int differing = 0, covered = 0;
    for (std::size_t p = 0; p < a.silhouette.data.size(); ++p) {
      differing += a.silhouette.data[p] != b.silhouette.data[p];
      covered += b.silhouette.data[p] != 0;
    }
    ASSERT_GT(covered, 1000) << view.name;
    EXPECT_LE(differing, covered / 500 + 1) << view.name;
    const Image mask = UnionMask(a.silhouette, b.silhouette);
    EXPECT_GT(MaskedPsnr(b.color, a.color, mask), 40.0) << view.name;
    // Outside the mesh: the background, in both; unseen surface: the mesh's colour, in both.
    int unseen = 0;
    for (std::size_t p = 0; p < a.silhouette.data.size(); ++p) {
      const std::uint8_t* ca = &a.color.data[3 * p];
      const std::uint8_t* cb = &b.color.data[3 * p];
      if (a.silhouette.data[p] == 0 && b.silhouette.data[p] == 0) {
        ASSERT_EQ(ca[0] + ca[1] + ca[2], 0) << view.name;
      } else if (cb[0] == 51 && cb[1] == 153 && cb[2] == 77) {
        ++unseen;
        ASSERT_TRUE(std::abs(ca[0] - 51) <= 1 && std::abs(ca[1] - 153) <= 1 && std::abs(ca[2] - 77) <= 1) << view.name;
      }
    }
    if (view.name == "below") {
      EXPECT_GT(unseen, 50);
    }
  }
}

TEST(ProjectiveTexturer, WideFeatherStillBlends) {
  // Feathering wider than the band distance handles (250 px) takes the full distance transform.
  SphereCapture sphere;
  ProjectiveTextureOptions options;
  options.feather_px = 300.0;
  ProjectiveTexturer texturer(sphere.real, options);
  texturer.SetFrame(sphere.real.vertices, sphere.ring, sphere.images, sphere.masks);
  const Camera view = RingCamera("between", 22.5, 1.5);
  const RenderResult expected = sphere.truth.Render(view);
  const RenderResult rendered = texturer.Render(view, true);
  EXPECT_GT(MaskedPsnr(expected.color, rendered.color, UnionMask(expected.silhouette, rendered.silhouette)), 30.0);
}

TEST(ProjectiveTexturer, BadInputThrows) {
  const Mesh grey = FlatSphere(0.5f, 0.5f, 0.5f);
  ProjectiveTexturer texturer(grey);
  EXPECT_THROW(texturer.Render(RingCamera("v", 0, 1)), UsageError);
  const std::vector<Camera> ring = Ring(2);
  EXPECT_THROW(texturer.SetFrame(grey.vertices, ring, {Image(160, 120, 3)}), UsageError);
  EXPECT_THROW(texturer.SetFrame(grey.vertices, ring, {Image(160, 120, 3), Image(80, 120, 3)}), InputError);
  EXPECT_THROW(texturer.SetFrame(grey.vertices.topRows(10), ring, {Image(160, 120, 3), Image(160, 120, 3)}),
               InputError);
  ProjectiveTextureOptions options;
  options.best_k = 0;
  EXPECT_THROW(ProjectiveTexturer(grey, options), UsageError);
}

}  // namespace
}  // namespace confluent
