// Silhouettes from rim edges (silhouette/rim_silhouette.h) against the facing-triangle fill
// (RasterizeClosedMesh) on closed meshes with concavities, folds and one part in front of
// another, seen from a ring of cameras with and without lens distortion.

#include "silhouette/rim_silhouette.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/mesh_ops.h"
#include "silhouette/overlap.h"
#include "tests/support/camera_ring.h"

namespace confluent {
namespace {

// A sphere with deep bumps (concave valleys that fold behind ridges from the side) and, beside
// it, a tilted capsule that passes in front of it in some views: one mesh of two closed parts.
Mesh BumpySphereAndCapsule() {
  Mesh sphere = MakeUvSphere(0.35, 60, 120);
  for (int v = 0; v < sphere.num_vertices(); ++v) {
    const Eigen::Vector3d p = sphere.vertices.row(v);
    const double theta = std::atan2(p.y(), p.x()), phi = std::acos(std::clamp(p.z() / 0.35, -1.0, 1.0));
    sphere.vertices.row(v) *= 1.0 + 0.3 * std::sin(5 * theta) * std::sin(4 * phi);
  }
  sphere.vertices.rowwise() += Eigen::RowVector3d(0.0, 0.0, 1.0);
  Mesh capsule = MakeCapsule(0.08, 0.9, 16, 32);
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 0.3, 0).normalized()).toRotationMatrix();
  capsule.vertices = (capsule.vertices * tilt.transpose()).rowwise() + Eigen::RowVector3d(0.45, 0.2, 1.1);
  Mesh both;
  both.vertices.resize(sphere.num_vertices() + capsule.num_vertices(), 3);
  both.vertices << sphere.vertices, capsule.vertices;
  both.faces.resize(sphere.num_faces() + capsule.num_faces(), 3);
  both.faces << sphere.faces, (capsule.faces.array() + sphere.num_vertices()).matrix();
  return both;
}

long Foreground(const Image& mask) {
  long count = 0;
  for (std::uint8_t value : mask.data) count += value != 0;
  return count;
}

long Differing(const Image& a, const Image& b) {
  long count = 0;
  for (std::size_t i = 0; i < a.data.size(); ++i) count += a.data[i] != b.data[i];
  return count;
}

TEST(RimSilhouette, MatchesTheFacingTriangleFillOnFoldsAndOverlaps) {
  const Mesh mesh = BumpySphereAndCapsule();
  const RimSilhouetteRasterizer rim(mesh.faces);
  ASSERT_TRUE(rim.closed());
  Rig rig = testing::CameraRing(8, 640, 480);
  for (int c = 0; c < 8; c += 2) rig.cameras[c].dist << -0.2, 0.05, 0.001, -0.001, 0.0;  // barrel distortion
  for (const Camera& camera : rig.cameras) {
    const Image expected = RasterizeClosedMesh(mesh, camera);
    const Image actual = rim.Rasterize(mesh.vertices, camera);
    ASSERT_EQ(actual.width, camera.width);
    ASSERT_EQ(actual.height, camera.height);
    const long foreground = Foreground(expected);
    ASSERT_GT(foreground, 5000) << camera.name;
    // Only pixel centres exactly on a rim edge may be drawn differently.
    EXPECT_LE(Differing(actual, expected), foreground / 5000) << camera.name;
  }
}

TEST(RimSilhouette, PosesOfTheSameTopologyNeedNoNewRasterizer) {
  Mesh mesh = BumpySphereAndCapsule();
  const RimSilhouetteRasterizer rim(mesh.faces);
  const Camera camera = testing::CameraRing(1, 640, 480).cameras[0];
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.9, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  mesh.vertices = ((mesh.vertices.rowwise() - Eigen::RowVector3d(0, 0, 1)) * turn.transpose()).rowwise() +
                  Eigen::RowVector3d(0.1, 0.0, 1.0);
  const Image expected = RasterizeClosedMesh(mesh, camera);
  EXPECT_LE(Differing(rim.Rasterize(mesh.vertices, camera), expected), Foreground(expected) / 5000);
}

TEST(RimSilhouette, OpenMeshesAndPointsBehindTheCameraFallBackToTheTriangleFill) {
  // An open mesh: the sphere without its first face.
  Mesh open = MakeUvSphere(0.3, 20, 40);
  open.vertices.rowwise() += Eigen::RowVector3d(0, 0, 1);
  open.faces = open.faces.bottomRows(open.num_faces() - 1).eval();
  const RimSilhouetteRasterizer rim_open(open.faces);
  EXPECT_FALSE(rim_open.closed());
  const Camera camera = testing::CameraRing(1, 320, 240).cameras[0];
  const Image expected_open = RasterizeClosedMesh(open, camera);
  EXPECT_GT(Foreground(expected_open), 1000);
  EXPECT_EQ(rim_open.Rasterize(open.vertices, camera).data, expected_open.data);
  // A closed mesh that reaches behind a camera close to it: the triangle fill's rule (skip the
  // triangles with a vertex behind the camera).
  const Mesh near = BumpySphereAndCapsule();
  const RimSilhouetteRasterizer rim_near(near.faces);
  ASSERT_TRUE(rim_near.closed());
  const Camera close_by = LookAtCamera("close", Eigen::Vector3d(0.6, 0.0, 1.0), Eigen::Vector3d(0.3, 0.6, 1.0), 320, 240, 352.0);
  int behind = 0;
  for (int v = 0; v < near.num_vertices(); ++v) behind += close_by.PointInCamera(near.vertices.row(v).transpose()).z() <= 0.0;
  ASSERT_GT(behind, 0);
  const Image expected_near = RasterizeClosedMesh(near, close_by);
  EXPECT_GT(Foreground(expected_near), 1000);
  EXPECT_EQ(rim_near.Rasterize(near.vertices, close_by).data, expected_near.data);
}

TEST(RimSilhouette, InconsistentlyOrientedFacesAreNotClosed) {
  Mesh sphere = MakeUvSphere(0.3, 12, 24);
  std::swap(sphere.faces(5, 0), sphere.faces(5, 1));
  EXPECT_FALSE(RimSilhouetteRasterizer(sphere.faces).closed());
  EXPECT_TRUE(RimSilhouetteRasterizer(MakeUvSphere(0.3, 12, 24).faces).closed());
}

}  // namespace
}  // namespace confluent
