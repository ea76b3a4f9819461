// MeshRenderer: pixel exactness against Camera::Project, mask/depth/id consistency against
// analytic geometry, colours, textures, vertex updates and bad input.

#include "render/renderer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "core/error.h"
#include "tests/render/renderer_test_util.h"

namespace confluent {
namespace {

using render_test::LookAtTestCamera;
using render_test::MakeDisc;
using render_test::MakeIcosphere;
using render_test::MakeSquare;
using render_test::TestCamera;

// Ray-sphere intersection: the camera z of the first hit along pixel `pixel`'s ray, or 0.
double SphereDepth(const Camera& camera, const Eigen::Vector2d& pixel, const Eigen::Vector3d& center, double radius) {
  const Eigen::Vector3d origin = camera.center_in_world();
  const Eigen::Vector3d ray = camera.RayInWorld(pixel);
  const Eigen::Vector3d oc = origin - center;
  const double b = ray.dot(oc);
  const double discriminant = b * b - (oc.squaredNorm() - radius * radius);
  if (discriminant < 0.0) return 0.0;
  const double distance = -b - std::sqrt(discriminant);
  return camera.PointInCamera(origin + distance * ray).z();
}

struct Blob {
  double sum_x = 0.0, sum_y = 0.0;
  int count = 0;
  Eigen::Vector2d centroid() const { return Eigen::Vector2d(sum_x / count, sum_y / count); }
};

// Even-odd point-in-polygon test.
bool InsidePolygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p) {
  bool inside = false;
  for (std::size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
      inside = !inside;
  }
  return inside;
}

// Centroid errors of rendered discs, in pixels, over all discs.
struct CentroidErrors {
  double max_px = 0.0;         // |rendered blob centroid - Camera::Project(disc centre)|
  double mean_px = 0.0;
  double raster_max_px = 0.0;  // |rendered blob centroid - centroid of the exact pixel set|
  double raster_mean_px = 0.0;
};

// Renders `num` discs (64-gons) parallel to the image plane, each imaged as a ~`radius_px` circle
// around a random sub-pixel position spread over the whole image (corners included, where the
// distortion is largest). Compares each rendered blob's centroid with Camera::Project of the
// disc centre, and with the centroid of the exact pixel set: the pixels whose ideal position
// (UndistortPixel) lies inside the polygon projected by the ideal camera.
CentroidErrors MeasureCentroidErrors(MeshRenderer* renderer, const Camera& camera, double radius_px, int num,
                                     unsigned seed) {
  constexpr int kSegments = 64;
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> jitter(-0.5, 0.5);
  std::vector<Eigen::Vector3d> centers;
  std::vector<std::vector<Eigen::Vector2d>> polygons;
  Camera ideal = camera;
  ideal.dist.setZero();
  const int columns = 8, rows = num / columns;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const Eigen::Vector2d pixel(
          radius_px + 2 + (camera.width - 2 * radius_px - 5) * c / (columns - 1.0) + jitter(random),
          radius_px + 2 + (camera.height - 2 * radius_px - 5) * r / (rows - 1.0) + jitter(random));
      const Eigen::Vector3d center = camera.Unproject(pixel, 2.5 + 0.1 * jitter(random));
      // Parallel to the image plane, so its ideal image is an ellipse centred exactly on the
      // projected centre (a tilted disc's image centroid moves by ~r^2/f under perspective).
      const double radius_m = radius_px * camera.PointInCamera(center).z() / camera.K(0, 0);
      const Mesh disc = MakeDisc(center, camera.optical_axis_in_world(), radius_m, kSegments);
      renderer->AddMesh(disc);
      centers.push_back(center);
      std::vector<Eigen::Vector2d> polygon;
      for (int v = 1; v <= kSegments; ++v) polygon.push_back(ideal.Project(disc.vertices.row(v).transpose()));
      polygons.push_back(polygon);
    }
  RenderRequest request;
  request.color = false;
  request.triangle_id = true;
  const RenderResult result = renderer->Render(camera, request);
  std::vector<Blob> blobs(centers.size()), exact(centers.size());
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const int id = result.triangle_id.at(x, y);
      if (id >= 0) {
        Blob& blob = blobs.at(id / kSegments);  // discs were uploaded in order
        blob.sum_x += x;
        blob.sum_y += y;
        ++blob.count;
      }
      const Eigen::Vector2d ideal_pixel = camera.UndistortPixel(Eigen::Vector2d(x, y));
      for (std::size_t i = 0; i < polygons.size(); ++i)
        if (InsidePolygon(polygons[i], ideal_pixel)) {
          exact[i].sum_x += x;
          exact[i].sum_y += y;
          ++exact[i].count;
        }
    }
  CentroidErrors errors;
  for (std::size_t i = 0; i < centers.size(); ++i) {
    EXPECT_GT(blobs[i].count, 0.5 * M_PI * radius_px * radius_px) << "disc " << i;  // barrel shrinks
    if (blobs[i].count == 0 || exact[i].count == 0) continue;
    const Eigen::Vector2d projected = camera.Project(centers[i]);
    const double error = (blobs[i].centroid() - projected).norm();
    const double raster_error = (blobs[i].centroid() - exact[i].centroid()).norm();
    if (std::getenv("RENDER_TEST_DEBUG"))
      std::printf("disc %2zu at %7.2f %7.2f: rendered - projected %+.3f %+.3f, rendered - exact %+.3f %+.3f\n", i,
                  projected.x(), projected.y(), blobs[i].centroid().x() - projected.x(),
                  blobs[i].centroid().y() - projected.y(), blobs[i].centroid().x() - exact[i].centroid().x(),
                  blobs[i].centroid().y() - exact[i].centroid().y());
    errors.max_px = std::max(errors.max_px, error);
    errors.mean_px += error / centers.size();
    errors.raster_max_px = std::max(errors.raster_max_px, raster_error);
    errors.raster_mean_px += raster_error / centers.size();
  }
  return errors;
}

std::string Describe(const CentroidErrors& errors) {
  char text[200];
  std::snprintf(text, sizeof(text), "vs projection: mean %.3f max %.3f px; vs exact raster: mean %.3f max %.3f px",
                errors.mean_px, errors.max_px, errors.raster_mean_px, errors.raster_max_px);
  return text;
}

// The criterion is < 0.5 px between projection and rendering. A half-pixel convention
// error would put every disc off by ~0.5-0.7 px, so the mean is held far below that; quantising
// a 6 px disc alone moves its centroid by ~0.05-0.1 px. Without distortion the rendered pixel set
// must equal the exact set (pixel centres inside the projected polygon), up to float rounding
// of a pixel centre lying on an edge.
TEST(MeshRenderer, ProjectedPointsMatchRenderedBlobCentroids) {
  MeshRenderer renderer;
  const CentroidErrors errors = MeasureCentroidErrors(&renderer, TestCamera(false), 6.0, 48, 1);
  EXPECT_LT(errors.max_px, 0.3) << Describe(errors);
  EXPECT_LT(errors.mean_px, 0.12) << Describe(errors);
  EXPECT_LT(errors.raster_mean_px, 0.01) << Describe(errors);
  EXPECT_LT(errors.raster_max_px, 0.1) << Describe(errors);  // float vs double at an edge
  RecordProperty("centroid_errors", Describe(errors));
}

// With distortion the remap through the ideal buffer resamples once more, so the blob follows the
// exact pixel set only approximately (sub-pixel outline from bilinear coverage).
TEST(MeshRenderer, ProjectedPointsMatchRenderedBlobCentroidsWithDistortion) {
  MeshRenderer renderer;
  const Camera camera = TestCamera(true);
  // The distortion is strong: corner pixels move by several pixels.
  const Eigen::Vector2d corner(0.0, 0.0);
  ASSERT_GT((camera.UndistortPixel(corner) - corner).norm(), 5.0);
  const CentroidErrors errors = MeasureCentroidErrors(&renderer, camera, 6.0, 48, 2);
  EXPECT_LT(errors.max_px, 0.5) << Describe(errors);
  EXPECT_LT(errors.mean_px, 0.2) << Describe(errors);
  EXPECT_LT(errors.raster_mean_px, 0.2) << Describe(errors);
  RecordProperty("centroid_errors", Describe(errors));
}

TEST(MeshRenderer, SquareCoversExactlyThePixelCentresInside) {
  // Axis-aligned square edges at half-integer pixel positions: the covered set is exact, and
  // the shared diagonal through pixel centres is covered exactly once (no cracks, no overlap).
  MeshRenderer renderer;
  Camera camera;
  camera.width = 64;
  camera.height = 48;
  camera.K << 40.0, 0.0, 31.5, 0.0, 40.0, 23.5, 0.0, 0.0, 1.0;
  Mesh square = MakeSquare(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 0.5);
  // Shift so the edges fall at 21.5..41.5 + 3 in x and 13.5..33.5 - 2 in y.
  for (int v = 0; v < 4; ++v) square.vertices.row(v) += Eigen::RowVector3d(3.0 / 40.0, -2.0 / 40.0, 0.0);
  renderer.AddMesh(square);
  RenderRequest request;
  request.color = false;
  request.silhouette = true;
  const RenderResult result = renderer.Render(camera, request);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const bool inside = x >= 25 && x <= 44 && y >= 12 && y <= 31;
      ASSERT_EQ(result.silhouette.at<std::uint8_t>(x, y), inside ? 255 : 0) << x << "," << y;
    }
}

// Silhouette == depth > 0 == id >= 0; all three match the analytic sphere per pixel except
// within two pixels of the outline; depth matches the sphere's camera z; the silhouette area
// matches the analytic area (per-pixel ray test of the camera itself) within 1%.
void CheckSphere(bool with_distortion, int supersampling = 1, double area_tolerance = 0.01) {
  MeshRendererOptions options;
  options.distortion_supersampling = supersampling;
  MeshRenderer renderer(options);
  const Camera camera = TestCamera(with_distortion);
  Camera ideal = camera;
  ideal.dist.setZero();
  const Eigen::Vector3d center(0.05, -0.02, 0.03);
  const double radius = 0.6;
  renderer.AddMesh(MakeIcosphere(center, radius, 5));
  RenderRequest request;
  request.color = true;
  request.depth = true;
  request.silhouette = true;
  request.triangle_id = true;
  const RenderResult result = renderer.Render(camera, request);
  ASSERT_EQ(result.depth.width, camera.width);
  ASSERT_EQ(result.silhouette.height, camera.height);
  int rendered_area = 0, analytic_area = 0, interior_checked = 0;
  double max_depth_error = 0.0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const bool mask = result.silhouette.at<std::uint8_t>(x, y) == 255;
      const float depth = result.depth.at<float>(x, y);
      const int id = result.triangle_id.at(x, y);
      ASSERT_TRUE(mask || result.silhouette.at<std::uint8_t>(x, y) == 0);
      ASSERT_EQ(mask, depth > 0.0f) << x << "," << y;
      ASSERT_EQ(mask, id >= 0) << x << "," << y;
      rendered_area += mask;
      analytic_area += SphereDepth(camera, Eigen::Vector2d(x, y), center, radius) > 0.0;
      // Truth at the pixel's ideal position. With distortion the remap reads ideal samples up
      // to 0.71 px away, so depth may differ by that much of the local depth gradient.
      const Eigen::Vector2d sampled = camera.UndistortPixel(Eigen::Vector2d(x, y));
      const double truth = SphereDepth(ideal, sampled, center, radius);
      bool interior = true;
      double gradient = 0.0;  // largest depth change to a neighbour 1 ideal px away
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          const double neighbour = SphereDepth(ideal, sampled + Eigen::Vector2d(dx, dy), center, radius);
          interior &= (neighbour > 0.0) == (truth > 0.0);
          if (std::abs(dx) + std::abs(dy) == 1) gradient = std::max(gradient, std::abs(neighbour - truth));
        }
      if (!interior) continue;
      ++interior_checked;
      ASSERT_EQ(mask, truth > 0.0) << x << "," << y;
      if (truth > 0.0) {
        const double allowance = with_distortion ? 0.75 * gradient : 0.0;
        max_depth_error = std::max(max_depth_error, std::abs(depth - truth) - allowance);
      }
    }
  EXPECT_GT(analytic_area, 3000);
  EXPECT_NEAR(rendered_area, analytic_area, area_tolerance * analytic_area);
  EXPECT_GT(interior_checked, camera.width * camera.height / 2);
  // The level-5 icosphere lies inside the sphere by ~0.2 mm (more along grazing rays).
  EXPECT_LT(max_depth_error, 1.5e-3);
  ::testing::Test::RecordProperty("max_depth_error_m", std::to_string(max_depth_error));
  ::testing::Test::RecordProperty("area_px", std::to_string(rendered_area) + " vs " + std::to_string(analytic_area));
}

TEST(MeshRenderer, SphereMaskDepthAndIdsAreConsistent) { CheckSphere(false); }
// With distortion and no supersampling, the outline is reconstructed from one ideal sample per
// pixel: each side of the disc may move by up to half a pixel, coherently along its length
// (measured: +1.8% area here). Supersampling 3x brings it within 1%.
TEST(MeshRenderer, SphereMaskDepthAndIdsAreConsistentWithDistortion) { CheckSphere(true, 1, 0.03); }
TEST(MeshRenderer, SphereMaskDepthAndIdsAreConsistentWithDistortionSupersampled) { CheckSphere(true, 3, 0.01); }

TEST(MeshRenderer, SphereSilhouetteAreaMatchesProjectedDisc) {
  // On the optical axis a sphere projects to a disc of radius f * tan(asin(R / D)).
  MeshRenderer renderer;
  Camera camera;
  camera.width = 160;
  camera.height = 120;
  camera.K << 120.0, 0.0, 79.5, 0.0, 120.0, 59.5, 0.0, 0.0, 1.0;
  const double radius = 0.5, distance = 2.0;
  renderer.AddMesh(MakeIcosphere(Eigen::Vector3d(0, 0, distance), radius, 5));
  RenderRequest request;
  request.color = false;
  request.silhouette = true;
  const RenderResult result = renderer.Render(camera, request);
  int area = 0;
  for (std::uint8_t value : result.silhouette.data) area += value == 255;
  const double disc_radius_px = 120.0 * std::tan(std::asin(radius / distance));
  const double analytic = M_PI * disc_radius_px * disc_radius_px;
  EXPECT_NEAR(area, analytic, 0.01 * analytic);
}

TEST(MeshRenderer, DepthOfATiltedPlaneIsCameraZ) {
  for (bool with_distortion : {false, true}) {
    MeshRenderer renderer;
    const Camera camera = TestCamera(with_distortion);
    const Eigen::Vector3d normal = Eigen::Vector3d(0.3, -1.0, 0.4).normalized();
    const Eigen::Vector3d point(0.1, 0.2, -0.1);
    const Eigen::Vector3d u = normal.unitOrthogonal(), v = normal.cross(u);
    renderer.AddMesh(MakeSquare(point, u, v, 40.0));
    RenderRequest request;
    request.color = false;
    request.depth = true;
    const RenderResult result = renderer.Render(camera, request);
    double max_error = 0.0;
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) {
        const Eigen::Vector3d origin = camera.center_in_world();
        const Eigen::Vector3d ray = camera.RayInWorld(Eigen::Vector2d(x, y));
        const double distance = (point - origin).dot(normal) / ray.dot(normal);
        const double truth = camera.PointInCamera(origin + distance * ray).z();
        ASSERT_GT(result.depth.at<float>(x, y), 0.0f) << "plane must fill the image, corners included";
        max_error = std::max(max_error, std::abs(result.depth.at<float>(x, y) - truth) / truth);
      }
    // Undistorted: float precision. Distorted: nearest ideal pixel, so up to half a pixel of
    // depth gradient.
    EXPECT_LT(max_error, with_distortion ? 5e-3 : 1e-5) << "distortion " << with_distortion;
  }
}

// Point-in-triangle for 2D points with a tolerance in pixels.
bool InsideTriangle(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                    const Eigen::Vector2d& c, double tolerance) {
  auto edge = [&](const Eigen::Vector2d& from, const Eigen::Vector2d& to) {
    const Eigen::Vector2d d = to - from;
    return (d.x() * (p.y() - from.y()) - d.y() * (p.x() - from.x())) / d.norm();
  };
  const double e0 = edge(a, b), e1 = edge(b, c), e2 = edge(c, a);
  return (e0 >= -tolerance && e1 >= -tolerance && e2 >= -tolerance) ||
         (e0 <= tolerance && e1 <= tolerance && e2 <= tolerance);
}

TEST(MeshRenderer, TriangleIdIsTheVisibleFaceUnderThePixel) {
  for (bool with_distortion : {false, true}) {
    MeshRenderer renderer;
    Camera camera = TestCamera(with_distortion);
    const Mesh sphere = MakeIcosphere(Eigen::Vector3d(0, 0, 0), 0.7, 3);
    renderer.AddMesh(sphere);
    RenderRequest request;
    request.color = false;
    request.depth = true;
    request.triangle_id = true;
    const RenderResult result = renderer.Render(camera, request);
    Camera ideal = camera;
    ideal.dist.setZero();
    int checked = 0;
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) {
        const int id = result.triangle_id.at(x, y);
        if (id < 0) continue;
        ASSERT_LT(id, sphere.num_faces());
        // With distortion the output pixel samples the nearest ideal pixel: up to 0.71 px away.
        const Eigen::Vector2d pixel = camera.UndistortPixel(Eigen::Vector2d(x, y));
        const Eigen::Vector2d a = ideal.Project(sphere.vertices.row(sphere.faces(id, 0)).transpose());
        const Eigen::Vector2d b = ideal.Project(sphere.vertices.row(sphere.faces(id, 1)).transpose());
        const Eigen::Vector2d c = ideal.Project(sphere.vertices.row(sphere.faces(id, 2)).transpose());
        ASSERT_TRUE(InsideTriangle(pixel, a, b, c, with_distortion ? 0.75 : 1e-3))
            << "pixel " << x << "," << y << " id " << id << " distortion " << with_distortion;
        // The face is front-facing (visible), i.e. its normal points towards the camera.
        const Eigen::Vector3d p0 = sphere.vertices.row(sphere.faces(id, 0)).transpose();
        const Eigen::Vector3d n = (sphere.vertices.row(sphere.faces(id, 1)).transpose() - p0)
                                      .cross(sphere.vertices.row(sphere.faces(id, 2)).transpose() - p0);
        ASSERT_GT(n.dot(camera.center_in_world() - p0), 0.0);
        ++checked;
      }
    EXPECT_GT(checked, 2000);
  }
}

TEST(MeshRenderer, UniformColourUnlitAndLit) {
  MeshRenderer renderer;
  Camera camera;
  camera.width = 80;
  camera.height = 60;
  camera.K << 60.0, 0.0, 39.5, 0.0, 60.0, 29.5, 0.0, 0.0, 1.0;
  Mesh square = MakeSquare(Eigen::Vector3d(0, 0, 2), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 1.0);
  const Eigen::Vector3f albedo(0.2f, 0.5f, 0.8f);
  square.colors.resize(4, 3);
  for (int v = 0; v < 4; ++v) square.colors.row(v) = albedo.transpose();
  square.uvs.resize(0, 2);
  square.face_uvs.resize(0, 3);
  renderer.AddMesh(square);

  RenderRequest request;
  request.silhouette = true;
  request.shading.lit = false;
  request.shading.srgb_output = false;
  request.shading.color_type = PixelType::kFloat32;
  request.shading.background = Eigen::Vector3d(0.1, 0.0, 0.3);
  RenderResult result = renderer.Render(camera, request);
  ASSERT_EQ(result.color.channels, 3);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const bool covered = result.silhouette.at<std::uint8_t>(x, y) == 255;
      for (int c = 0; c < 3; ++c)
        ASSERT_NEAR(result.color.at<float>(x, y, c), covered ? albedo[c] : request.shading.background[c], 1e-6);
    }

  // 8-bit sRGB output: the encoded value of the albedo.
  request.shading.srgb_output = true;
  request.shading.color_type = PixelType::kUInt8;
  result = renderer.Render(camera, request);
  for (int c = 0; c < 3; ++c) {
    const double linear = albedo[c];
    const double encoded = linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
    EXPECT_NEAR(result.color.at<std::uint8_t>(40, 30, c), encoded * 255.0, 1.0);
  }

  // Lambert with a headlight: the square faces the camera, so at the principal point
  // colour = albedo * (ambient + diffuse).
  request.shading.lit = true;
  request.shading.headlight = true;
  request.shading.ambient = 0.25;
  request.shading.diffuse = 0.5;
  request.shading.srgb_output = false;
  request.shading.color_type = PixelType::kFloat32;
  result = renderer.Render(camera, request);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(result.color.at<float>(40, 30, c), albedo[c] * 0.75, 1e-3);
  // Light from behind the surface (world -z is towards the camera here): ambient only.
  request.shading.headlight = false;
  request.shading.light_direction_in_world = Eigen::Vector3d(0, 0, 1);
  result = renderer.Render(camera, request);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(result.color.at<float>(40, 30, c), albedo[c] * 0.25, 1e-3);
}

TEST(MeshRenderer, TextureIsSampledWithVUp) {
  MeshRenderer renderer;
  Camera camera;
  camera.width = 80;
  camera.height = 80;
  camera.K << 60.0, 0.0, 39.5, 0.0, 60.0, 39.5, 0.0, 0.0, 1.0;
  // Square facing the camera: u along image x, v along image -y (up in the image).
  const Mesh square = MakeSquare(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitY(), 1.0);
  // 8x8 float texture, quadrants: top-left red, top-right green, bottom-left blue, bottom-right white.
  Image texture(8, 8, 3, PixelType::kFloat32);
  const float quadrant[2][2][3] = {{{1, 0, 0}, {0, 1, 0}}, {{0, 0, 1}, {1, 1, 1}}};
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x)
      for (int c = 0; c < 3; ++c) texture.at<float>(x, y, c) = quadrant[y / 4][x / 4][c];
  renderer.AddMesh(square, "textured square", texture);
  RenderRequest request;
  request.shading.lit = false;
  request.shading.srgb_output = false;
  request.shading.color_type = PixelType::kFloat32;
  const RenderResult result = renderer.Render(camera, request);
  // The square spans pixels 9.5..69.5; quadrant centres at 24.5 and 54.5 -> sample 24/25, 54/55.
  const int samples[2] = {24, 55};
  for (int qy = 0; qy < 2; ++qy)
    for (int qx = 0; qx < 2; ++qx)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(result.color.at<float>(samples[qx], samples[qy], c), quadrant[qy][qx][c], 1e-2)
            << "quadrant " << qx << "," << qy << " channel " << c;
}

TEST(MeshRenderer, UpdateVerticesMovesTheSilhouette) {
  MeshRenderer renderer;
  const Camera camera = TestCamera(false);
  Mesh sphere = MakeIcosphere(Eigen::Vector3d(0, 0, 0), 0.3, 3);
  const int handle = renderer.AddMesh(sphere);
  RenderRequest request;
  request.color = false;
  request.silhouette = true;
  for (const Eigen::Vector3d& offset : {Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.4, 0.1, -0.2)}) {
    RowMatrixX3d moved = sphere.vertices;
    moved.rowwise() += offset.transpose();
    renderer.UpdateVertices(handle, moved);
    const RenderResult result = renderer.Render(camera, request);
    double sx = 0, sy = 0;
    int n = 0;
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x)
        if (result.silhouette.at<std::uint8_t>(x, y)) {
          sx += x;
          sy += y;
          ++n;
        }
    ASSERT_GT(n, 100);
    // A sphere's silhouette centroid is close to (not exactly at) its projected centre.
    EXPECT_LT((Eigen::Vector2d(sx / n, sy / n) - camera.Project(offset)).norm(), 1.0);
  }
}

TEST(MeshRenderer, SeveralMeshesAndIdOffsets) {
  MeshRenderer renderer;
  const Camera camera = TestCamera(false);
  const Mesh a = MakeIcosphere(Eigen::Vector3d(-0.4, 0, 0), 0.25, 2);
  const Mesh b = MakeIcosphere(Eigen::Vector3d(0.4, 0, 0), 0.25, 2);
  const int ha = renderer.AddMesh(a), hb = renderer.AddMesh(b);
  EXPECT_EQ(renderer.num_meshes(), 2);
  EXPECT_EQ(renderer.id_offset(ha), 0);
  EXPECT_EQ(renderer.id_offset(hb), a.num_faces());
  RenderRequest request;
  request.color = false;
  request.triangle_id = true;
  int count_a = 0, count_b = 0;
  RenderResult all = renderer.Render(camera, request);
  for (int id : all.triangle_id.ids) {
    count_a += id >= 0 && id < a.num_faces();
    count_b += id >= a.num_faces();
  }
  EXPECT_GT(count_a, 100);
  EXPECT_GT(count_b, 100);
  request.meshes = {hb};
  const RenderResult only_b = renderer.Render(camera, request);
  for (std::size_t i = 0; i < only_b.triangle_id.ids.size(); ++i) {
    const int id = only_b.triangle_id.ids[i];
    ASSERT_TRUE(id == -1 || id >= a.num_faces());
    if (all.triangle_id.ids[i] >= a.num_faces()) {
      ASSERT_EQ(id, all.triangle_id.ids[i]);
    }
  }
  request.meshes = {7};
  EXPECT_THROW(renderer.Render(camera, request), UsageError);
}

TEST(MeshRenderer, BackFaceCullingKeepsClosedMeshImagesIdentical) {
  for (bool with_distortion : {false, true}) {
    MeshRenderer renderer;
    const Camera camera = TestCamera(with_distortion);
    renderer.AddMesh(MakeIcosphere(Eigen::Vector3d(0.1, 0, 0), 0.5, 3));
    RenderRequest request;
    request.depth = request.silhouette = request.triangle_id = true;
    const RenderResult full = renderer.Render(camera, request);
    request.cull_back_faces = true;
    const RenderResult culled = renderer.Render(camera, request);
    EXPECT_EQ(full.triangle_id.ids, culled.triangle_id.ids);
    EXPECT_EQ(full.silhouette.data, culled.silhouette.data);
    EXPECT_EQ(full.depth.data, culled.depth.data);
    EXPECT_EQ(full.color.data, culled.color.data);
  }
  // Seen from inside, every face is a back face: culling leaves nothing.
  MeshRenderer renderer;
  renderer.AddMesh(MakeIcosphere(Eigen::Vector3d::Zero(), 5.0, 2));
  RenderRequest request;
  request.color = false;
  request.silhouette = true;
  request.cull_back_faces = true;
  const RenderResult inside = renderer.Render(TestCamera(false), request);
  for (std::uint8_t value : inside.silhouette.data) ASSERT_EQ(value, 0);
}

TEST(MeshRenderer, StrongBarrelDistortionFillsTheCorners) {
  MeshRenderer renderer;
  Camera camera = TestCamera(false);
  camera.dist << -0.45, 0.15, 0.0, 0.0, 0.0;
  // A huge plane behind the origin fills the whole (wide, undistorted) field of view.
  const Eigen::Vector3d axis = camera.optical_axis_in_world();
  renderer.AddMesh(MakeSquare(camera.center_in_world() + 3.0 * axis, axis.unitOrthogonal(),
                              axis.cross(axis.unitOrthogonal()), 200.0));
  RenderRequest request;
  request.color = false;
  request.silhouette = true;
  const RenderResult result = renderer.Render(camera, request);
  for (std::uint8_t value : result.silhouette.data) ASSERT_EQ(value, 255);
}

TEST(MeshRendererBadInput, InvertedOrDegenerateCameraIsAnInputError) {
  MeshRenderer renderer;
  renderer.AddMesh(MakeIcosphere(Eigen::Vector3d::Zero(), 0.5, 1));
  Camera mirrored = TestCamera(false);
  mirrored.rotation.row(0) *= -1.0;  // det = -1
  try {
    renderer.Render(mirrored);
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("rotation"), std::string::npos) << error.what();
  }
  Camera zero_focal = TestCamera(false);
  zero_focal.K(0, 0) = 0.0;
  try {
    renderer.Render(zero_focal);
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("focal"), std::string::npos) << error.what();
  }
  Camera nan_camera = TestCamera(false);
  nan_camera.translation.x() = std::nan("");
  EXPECT_THROW(renderer.Render(nan_camera), InputError);
  Camera empty = TestCamera(false);
  empty.width = 0;
  EXPECT_THROW(renderer.Render(empty), InputError);
  Camera huge = TestCamera(false);
  huge.width = 1 << 20;
  EXPECT_THROW(renderer.Render(huge), InputError);
  // The renderer still works after the errors.
  EXPECT_NO_THROW(renderer.Render(TestCamera(false)));
}

TEST(MeshRendererBadInput, NanVerticesAndBadFacesAreInputErrors) {
  MeshRenderer renderer;
  Mesh mesh = MakeIcosphere(Eigen::Vector3d::Zero(), 0.5, 1);
  Mesh with_nan = mesh;
  with_nan.vertices(7, 1) = std::nan("");
  try {
    renderer.AddMesh(with_nan, "body.ply");
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_EQ(error.path(), "body.ply");
    EXPECT_NE(std::string(error.what()).find("vertex 7"), std::string::npos) << error.what();
  }
  Mesh bad_face = mesh;
  bad_face.faces(3, 2) = 1000;
  EXPECT_THROW(renderer.AddMesh(bad_face), InputError);
  Mesh bad_colors = mesh;
  bad_colors.colors.resize(3, 3);
  EXPECT_THROW(renderer.AddMesh(bad_colors), InputError);
  EXPECT_EQ(renderer.num_meshes(), 0);

  const int handle = renderer.AddMesh(mesh, "body.ply");
  RowMatrixX3d moved = mesh.vertices;
  moved(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(renderer.UpdateVertices(handle, moved), InputError);
  EXPECT_THROW(renderer.UpdateVertices(handle, mesh.vertices.topRows(5)), InputError);
  EXPECT_THROW(renderer.UpdateVertices(3, mesh.vertices), UsageError);
  EXPECT_NO_THROW(renderer.Render(TestCamera(true)));
}

TEST(MeshRendererBadInput, MissingTextureFileIsAnInputError) {
  MeshRenderer renderer;
  Mesh square = MakeSquare(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 1.0);
  square.texture_path = "/nonexistent/texture.png";
  try {
    renderer.AddMesh(square);
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("/nonexistent/texture.png"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace confluent
