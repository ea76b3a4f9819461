// CpuRasterizer: analytic depth of a plane and a sphere, no gaps between triangles, back-face
// culling, near-plane clipping, row bands, and agreement with MeshRenderer (GL).

#include "render/cpu_raster.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/mesh_ops.h"
#include "render/renderer.h"
#include "tests/render/renderer_test_util.h"

namespace confluent {
namespace {

using render_test::LookAtTestCamera;
using render_test::MakeIcosphere;

// A (n x n)-quad grid of side `size` in the plane through `center` spanned by unit u, v (normal
// u x v; faces counter-clockwise seen from the side the normal points to).
Mesh MakeGrid(const Eigen::Vector3d& center, const Eigen::Vector3d& u, const Eigen::Vector3d& v, double size, int n) {
  Mesh mesh;
  mesh.vertices.resize((n + 1) * (n + 1), 3);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      mesh.vertices.row(j * (n + 1) + i) =
          (center + size * ((i / static_cast<double>(n) - 0.5) * u + (j / static_cast<double>(n) - 0.5) * v))
              .transpose();
  mesh.faces.resize(2 * n * n, 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      mesh.faces.row(2 * (j * n + i)) << a, b, c;
      mesh.faces.row(2 * (j * n + i) + 1) << a, c, d;
    }
  return mesh;
}

// Camera z where the ray through `pixel` meets the plane n . X = n . point (world), or 0.
double PlaneDepth(const Camera& camera, const Eigen::Vector2d& pixel, const Eigen::Vector3d& point,
                  const Eigen::Vector3d& normal) {
  const Eigen::Vector3d ray = camera.RayInWorld(pixel), C = camera.center_in_world();
  const double t = normal.dot(point - C) / normal.dot(ray);
  return t > 0 ? camera.PointInCamera(C + t * ray).z() : 0.0;
}

TEST(CpuRasterizer, TiltedPlaneHasAnalyticDepthAndNoGaps) {
  const Camera camera = LookAtTestCamera(Eigen::Vector3d(0.3, -3.0, 0.8), Eigen::Vector3d(0, 0, 0), 160, 120, 150.0);
  // Normal towards the camera side (-y, tilted): front faces.
  const Eigen::Vector3d normal = Eigen::Vector3d(0.2, -1.0, 0.3).normalized();
  const Eigen::Vector3d u = Eigen::Vector3d::UnitZ().cross(normal).normalized();
  const Eigen::Vector3d v = normal.cross(u);  // u x v = normal
  const Mesh grid = MakeGrid(Eigen::Vector3d(0.05, 0.1, 0.02), u, v, 1.2, 23);
  ASSERT_GT(normal.dot(camera.center_in_world() - Eigen::Vector3d(0.05, 0.1, 0.02)), 0.0) << "test setup: front faces";
  CpuRasterizer rasterizer(grid.faces, grid.num_vertices());
  CpuRasterFrame frame;
  std::vector<float> depth;
  const PixelBox box = rasterizer.DrawDepth(camera, grid.vertices.cast<float>(), &frame, &depth);
  ASSERT_FALSE(box.empty());
  int inside = 0, checked_edges = 0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const Eigen::Vector2d pixel(x, y);
      const double z = PlaneDepth(camera, pixel, grid.vertices.row(0).transpose(), normal);
      // Inside the square (with a margin of a hundredth of its side): must be drawn, exactly.
      const Eigen::Vector3d X = camera.Unproject(pixel, z) - Eigen::Vector3d(0.05, 0.1, 0.02);
      const double a = std::abs(X.dot(u)), b = std::abs(X.dot(v));
      const float got = depth[static_cast<std::size_t>(y) * camera.width + x];
      if (z > 0 && a < 0.6 * 0.99 && b < 0.6 * 0.99) {
        ++inside;
        ASSERT_NEAR(got, z, 1e-4 * z) << x << "," << y;
        EXPECT_TRUE(x >= box.x0 && x < box.x1 && y >= box.y0 && y < box.y1);
      } else if (z <= 0 || a > 0.6 * 1.01 || b > 0.6 * 1.01) {
        ASSERT_EQ(got, 0.0f) << x << "," << y;
      } else {
        ++checked_edges;
      }
    }
  EXPECT_GT(inside, 3000);
  EXPECT_GT(checked_edges, 0);

  // Seen from behind: culled by default, drawn (same depth) without culling.
  Mesh flipped = grid;
  flipped.faces.col(1).swap(flipped.faces.col(2));
  CpuRasterizer culled(flipped.faces, flipped.num_vertices());
  std::vector<float> back;
  EXPECT_TRUE(culled.DrawDepth(camera, flipped.vertices.cast<float>(), &frame, &back).empty());
  for (float value : back) ASSERT_EQ(value, 0.0f);
  CpuRasterOptions both_sides;
  both_sides.cull_back_faces = false;
  CpuRasterizer unculled(flipped.faces, flipped.num_vertices(), both_sides);
  unculled.DrawDepth(camera, flipped.vertices.cast<float>(), &frame, &back);
  EXPECT_EQ(back, depth);
}

TEST(CpuRasterizer, SphereDepthMatchesTheAnalyticSurface) {
  const Eigen::Vector3d center(0.1, -0.05, 0.2);
  const double radius = 0.5;
  const Mesh sphere = MakeIcosphere(center, radius, 4);  // 5120 faces
  const Camera camera = LookAtTestCamera(Eigen::Vector3d(0.5, -2.5, 0.9), center, 160, 120, 150.0);
  CpuRasterizer rasterizer(sphere.faces, sphere.num_vertices());
  CpuRasterFrame frame;
  std::vector<float> depth;
  rasterizer.DrawDepth(camera, sphere.vertices.cast<float>(), &frame, &depth);
  // Chord sagitta of the subdivided icosahedron: edge ~ 0.02 * radius ... well below 1 cm here.
  int hits = 0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const Eigen::Vector3d C = camera.center_in_world(), d = camera.RayInWorld(Eigen::Vector2d(x, y));
      const Eigen::Vector3d oc = C - center;
      const double b = oc.dot(d), disc = b * b - (oc.squaredNorm() - radius * radius);
      const float got = depth[static_cast<std::size_t>(y) * camera.width + x];
      if (disc > 0.05 * radius * radius) {  // well inside the outline
        const double z = camera.PointInCamera(C + (-b - std::sqrt(disc)) * d).z();
        ASSERT_GT(got, z - 1e-4) << x << "," << y << ": the polyhedron lies inside the sphere";
        ASSERT_LT(got, z + 0.006) << x << "," << y;
        ++hits;
      } else if (disc < 0) {
        ASSERT_EQ(got, 0.0f) << x << "," << y;
      }
    }
  EXPECT_GT(hits, 2000);
}

// A second frame drawn into the same buffer, clearing only the box the first one returned, equals
// a fresh draw: nothing of the first frame is left behind.
TEST(CpuRasterizer, RedrawClearsWhatThePreviousFrameDrew) {
  const Mesh sphere = MakeIcosphere(Eigen::Vector3d(0, 0, 0), 0.5, 3);
  const Camera camera = LookAtTestCamera(Eigen::Vector3d(0.5, -2.5, 0.9), Eigen::Vector3d::Zero(), 160, 120, 150.0);
  CpuRasterizer rasterizer(sphere.faces, sphere.num_vertices());
  CpuRasterFrame frame;
  std::vector<float> reused, fresh;
  const PixelBox first = rasterizer.DrawDepth(camera, sphere.vertices.cast<float>(), &frame, &reused);
  RowMatrixX3f moved = sphere.vertices.cast<float>();
  moved.col(0).array() += 0.4f;
  moved *= 0.5f;
  const PixelBox second = rasterizer.DrawDepth(camera, moved, &frame, &reused, &first);
  rasterizer.DrawDepth(camera, moved, &frame, &fresh);
  ASSERT_FALSE(first.empty());
  EXPECT_LT(second.x1 - second.x0, first.x1 - first.x0);  // the first frame covered more
  EXPECT_EQ(reused, fresh);
}

TEST(CpuRasterizer, AgreesWithMeshRendererDepthAndTriangleIds) {
  Mesh mesh = MakeUvSphere(0.6, 40, 80);
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = mesh.vertices.row(v).transpose();
    mesh.vertices.row(v) = (p * (1.0 + 0.1 * std::sin(5 * p.x()) * std::cos(4 * p.z()))).transpose();
  }
  MeshRenderer renderer;
  renderer.AddMesh(mesh);
  CpuRasterizer rasterizer(mesh.faces, mesh.num_vertices());
  const RowMatrixX3f vertices = mesh.vertices.cast<float>();
  for (const Eigen::Vector3d& eye : {Eigen::Vector3d(2.2, -1.0, 0.7), Eigen::Vector3d(-0.3, 2.0, -1.5)}) {
    const Camera camera = LookAtTestCamera(eye, Eigen::Vector3d(0.05, 0, 0), 200, 150, 180.0);
    RenderRequest request;
    request.color = false;
    request.depth = true;
    request.triangle_id = true;
    request.cull_back_faces = true;
    const RenderResult gl = renderer.Render(camera, request);
    CpuRasterFrame frame;
    rasterizer.Project(camera, vertices, &frame);
    const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
    std::vector<float> inverse_depth(pixels, 0.0f);
    std::vector<std::int32_t> ids(pixels, -1);
    // Two row bands, as two threads would draw them.
    rasterizer.Draw(frame, 0, 70, inverse_depth.data(), ids.data());
    rasterizer.Draw(frame, 70, camera.height, inverse_depth.data(), ids.data());
    int covered = 0, coverage_differs = 0, id_differs = 0;
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * camera.width + x;
        const float gl_z = gl.depth.at<float>(x, y);
        const bool cpu_covered = inverse_depth[p] > 0.0f;
        covered += gl_z > 0.0f;
        if ((gl_z > 0.0f) != cpu_covered) {
          ++coverage_differs;
          continue;
        }
        if (!cpu_covered) {
          ASSERT_EQ(ids[p], -1);
          continue;
        }
        if (ids[p] != gl.triangle_id.at(x, y)) {
          ++id_differs;  // a pixel centre on an edge: a neighbouring face, nearly the same depth
          ASSERT_NEAR(1.0f / inverse_depth[p], gl_z, 0.01f) << x << "," << y;
        } else {
          ASSERT_NEAR(1.0f / inverse_depth[p], gl_z, 1e-4f * gl_z) << x << "," << y;
        }
      }
    ASSERT_GT(covered, 5000);
    // Pixel centres exactly on an edge may go either way (different fill conventions).
    EXPECT_LE(coverage_differs, covered / 1000);
    EXPECT_LE(id_differs, covered / 500);
  }
}

TEST(CpuRasterizer, ClipsAtTheNearPlane) {
  // A large floor passing under and behind the camera: only the part in front is drawn, with the
  // analytic depth, and nothing behind the camera folds into the image.
  const Camera camera = LookAtTestCamera(Eigen::Vector3d(0, 0, 0.5), Eigen::Vector3d(0, 3, 0.0), 160, 120, 100.0);
  const Mesh floor = MakeGrid(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 40.0, 4);
  CpuRasterOptions options;
  options.near_m = 0.05;
  CpuRasterizer rasterizer(floor.faces, floor.num_vertices(), options);
  CpuRasterFrame frame;
  std::vector<float> depth;
  rasterizer.DrawDepth(camera, floor.vertices.cast<float>(), &frame, &depth);
  int drawn = 0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const double z = PlaneDepth(camera, Eigen::Vector2d(x, y), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
      const Eigen::Vector3d X = z > 0 ? camera.Unproject(Eigen::Vector2d(x, y), z) : Eigen::Vector3d(1e9, 0, 0);
      const float got = depth[static_cast<std::size_t>(y) * camera.width + x];
      if (z > 0 && std::abs(X.x()) < 19.5 && std::abs(X.y()) < 19.5) {
        ASSERT_NEAR(got, z, 1e-4 * z + 1e-5) << x << "," << y;
        ++drawn;
      } else if (z <= 0) {
        ASSERT_EQ(got, 0.0f) << x << "," << y << " (above the horizon)";
      }
    }
  EXPECT_GT(drawn, 5000);
}

TEST(CpuRasterizer, BadInputThrows) {
  RowMatrixX3i faces(1, 3);
  faces << 0, 1, 3;
  EXPECT_THROW(CpuRasterizer(faces, 3), InputError);
  CpuRasterOptions options;
  options.far_m = options.near_m;
  EXPECT_THROW(options.Check(), UsageError);
}

}  // namespace
}  // namespace confluent
