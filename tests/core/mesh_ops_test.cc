#include "core/mesh_ops.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/mesh_validation.h"

namespace confluent {
namespace {

// Every face normal points away from `centre` (checked at the face centroid).
void ExpectOutward(const Mesh& mesh, const Eigen::Vector3d& centre) {
  const RowMatrixX3d normals = FaceNormals(mesh);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) centroid += mesh.vertices.row(mesh.faces(f, k)).transpose() / 3.0;
    EXPECT_GT(normals.row(f).dot((centroid - centre).normalized()), 0.1) << "face " << f;
  }
}

TEST(MeshOps, SingleTriangleNormalAndArea) {
  Mesh mesh;
  mesh.vertices.resize(3, 3);
  mesh.vertices << 0, 0, 0, 2, 0, 0, 0, 3, 0;
  mesh.faces.resize(1, 3);
  mesh.faces << 0, 1, 2;
  EXPECT_EQ(FaceNormals(mesh).row(0), Eigen::RowVector3d(0, 0, 1));
  EXPECT_DOUBLE_EQ(FaceAreas(mesh)(0), 3.0);
  mesh.faces << 0, 2, 1;
  EXPECT_EQ(FaceNormals(mesh).row(0), Eigen::RowVector3d(0, 0, -1));
  EXPECT_EQ(VertexNormals(mesh).row(1), Eigen::RowVector3d(0, 0, -1));
  mesh.vertices.row(2) << 4, 0, 0;  // collinear
  EXPECT_EQ(FaceNormals(mesh).row(0), Eigen::RowVector3d::Zero());
}

TEST(MeshOps, VertexNormalsAreAreaWeighted) {
  // Vertex 0 is shared by a big face in the xy plane (area 8) and a small one in the xz plane
  // (area 0.5); the normal leans towards the big face's normal in the ratio 8 : 0.5.
  Mesh mesh;
  mesh.vertices.resize(5, 3);
  mesh.vertices << 0, 0, 0, 4, 0, 0, 0, 4, 0, 1, 0, 0, 0, 0, 1;
  mesh.faces.resize(2, 3);
  mesh.faces << 0, 1, 2, 0, 4, 3;  // normals +z and +y
  const Eigen::RowVector3d expected = Eigen::RowVector3d(0, 0.5, 8).normalized();
  EXPECT_NEAR((VertexNormals(mesh).row(0) - expected).norm(), 0.0, 1e-12);
}

TEST(MeshOps, BoxIsWatertightOutwardWithExactVolumeAndArea) {
  const Eigen::Vector3d low(-1, 0.5, 2), high(2, 1.5, 2.25);
  const Mesh box = MakeBox(low, high);
  EXPECT_EQ(box.num_vertices(), 8);
  EXPECT_EQ(box.num_faces(), 12);
  EXPECT_TRUE(ValidateMesh(box).is_watertight());
  ExpectOutward(box, 0.5 * (low + high));
  const Eigen::Vector3d size = high - low;
  EXPECT_NEAR(SignedVolume(box), size.prod(), 1e-12);
  EXPECT_NEAR(FaceAreas(box).sum(), 2 * (size.x() * size.y() + size.y() * size.z() + size.x() * size.z()), 1e-12);
  const Eigen::AlignedBox3d bounds = BoundingBox(box);
  EXPECT_EQ(bounds.min(), low);
  EXPECT_EQ(bounds.max(), high);
  EXPECT_TRUE(BoundingBox(Mesh{}).isEmpty());
}

TEST(MeshOps, UvSphereGeometry) {
  const double radius = 0.8;
  const Mesh sphere = MakeUvSphere(radius, 24, 32);
  EXPECT_EQ(sphere.num_vertices(), 2 + 23 * 32);
  EXPECT_EQ(sphere.num_faces(), 2 * 32 * 23);
  EXPECT_TRUE(ValidateMesh(sphere).is_watertight());
  EXPECT_TRUE(ValidateMesh(sphere).is_clean());
  ExpectOutward(sphere, Eigen::Vector3d::Zero());
  for (int v = 0; v < sphere.num_vertices(); ++v) EXPECT_NEAR(sphere.vertices.row(v).norm(), radius, 1e-12);
  // The inscribed polyhedron's volume and area are a little below the sphere's.
  const double volume = 4.0 / 3.0 * M_PI * std::pow(radius, 3), area = 4 * M_PI * radius * radius;
  EXPECT_LT(SignedVolume(sphere), volume);
  EXPECT_GT(SignedVolume(sphere), 0.98 * volume);
  EXPECT_LT(FaceAreas(sphere).sum(), area);
  EXPECT_GT(FaceAreas(sphere).sum(), 0.98 * area);
  const RowMatrixX3d normals = VertexNormals(sphere);
  for (int v = 0; v < sphere.num_vertices(); ++v)
    EXPECT_GT(normals.row(v).dot(sphere.vertices.row(v) / radius), 0.999);
  EXPECT_NEAR(BoundingBox(sphere).max().z(), radius, 1e-12);
}

TEST(MeshOps, CapsuleGeometry) {
  const double radius = 0.1, length = 0.5;
  const Mesh capsule = MakeCapsule(radius, length, 12, 36);
  EXPECT_EQ(capsule.num_vertices(), 2 + 2 * 12 * 36);
  const MeshReport report = ValidateMesh(capsule);
  EXPECT_TRUE(report.is_watertight());
  EXPECT_TRUE(report.is_clean());
  ExpectOutward(capsule, Eigen::Vector3d::Zero());
  const Eigen::AlignedBox3d bounds = BoundingBox(capsule);
  EXPECT_NEAR(bounds.max().z(), length / 2 + radius, 1e-12);
  EXPECT_NEAR(bounds.min().z(), -length / 2 - radius, 1e-12);
  EXPECT_NEAR(bounds.max().x(), radius, 1e-12);
  const double volume = M_PI * radius * radius * length + 4.0 / 3.0 * M_PI * std::pow(radius, 3);
  EXPECT_NEAR(SignedVolume(capsule), volume, 0.02 * volume);
  // Zero length gives a sphere without a doubled equator.
  const Mesh ball = MakeCapsule(radius, 0.0, 3, 8);
  EXPECT_EQ(ball.num_vertices(), 2 + 5 * 8);
  EXPECT_TRUE(ValidateMesh(ball).is_clean());
}

TEST(MeshOps, SubdivideMidpointSplitsSharedEdgesOnce) {
  Mesh box = MakeBox(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 2, 3));
  box.colors.resize(8, 3);
  for (int v = 0; v < 8; ++v) box.colors.row(v) << v / 8.0f, 1.0f - v / 8.0f, 0.5f;
  box.uvs = box.vertices.leftCols(2);
  box.face_uvs = box.faces;
  for (int f = 0; f < 12; ++f) box.face_labels.push_back(f / 2);
  const Mesh fine = SubdivideMidpoint(box);
  EXPECT_EQ(fine.num_faces(), 48);
  EXPECT_EQ(fine.num_vertices(), 8 + 18);  // one new vertex per edge (12 box edges + 6 diagonals)
  EXPECT_TRUE(ValidateMesh(fine).is_watertight());
  EXPECT_NEAR(SignedVolume(fine), 6.0, 1e-12);
  ExpectOutward(fine, Eigen::Vector3d(0.5, 1, 1.5));
  ASSERT_TRUE(fine.has_colors());
  ASSERT_TRUE(fine.has_uvs());
  ASSERT_TRUE(fine.has_face_labels());
  // Child 0 of face f is (a, ab, ca): its second vertex is the midpoint of a and b.
  for (int f = 0; f < 12; ++f) {
    const int a = box.faces(f, 0), b = box.faces(f, 1), ab = fine.faces(4 * f, 1);
    EXPECT_EQ(fine.faces(4 * f, 0), a);
    EXPECT_NEAR((fine.vertices.row(ab) - 0.5 * (box.vertices.row(a) + box.vertices.row(b))).norm(), 0, 1e-15);
    EXPECT_NEAR((fine.colors.row(ab) - 0.5f * (box.colors.row(a) + box.colors.row(b))).norm(), 0, 1e-7);
    EXPECT_NEAR((fine.uvs.row(fine.face_uvs(4 * f, 1)) - fine.vertices.row(ab).leftCols(2)).norm(), 0, 1e-15);
    for (int c = 0; c < 4; ++c) EXPECT_EQ(fine.face_labels[4 * f + c], f / 2);
  }
  // Areas are preserved exactly on flat faces.
  EXPECT_NEAR(FaceAreas(fine).sum(), FaceAreas(box).sum(), 1e-12);
}

}  // namespace
}  // namespace confluent
