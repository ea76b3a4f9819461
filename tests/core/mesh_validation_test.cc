#include "core/mesh_validation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/mesh_ops.h"

namespace confluent {
namespace {

// Appends `b` to `a` (indices shifted), like two separate objects in one file.
Mesh Concatenate(const Mesh& a, const Mesh& b) {
  Mesh out;
  out.vertices.resize(a.num_vertices() + b.num_vertices(), 3);
  out.vertices << a.vertices, b.vertices;
  out.faces.resize(a.num_faces() + b.num_faces(), 3);
  out.faces << a.faces, (b.faces.array() + a.num_vertices()).matrix();
  return out;
}

// A cylinder without caps: `segments` columns, 3 rings of vertices.
Mesh OpenCylinder(int segments) {
  Mesh mesh;
  mesh.vertices.resize(3 * segments, 3);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < segments; ++j) {
      const double theta = 2 * M_PI * j / segments;
      mesh.vertices.row(i * segments + j) << std::cos(theta), std::sin(theta), 0.5 * i;
    }
  mesh.faces.resize(2 * 2 * segments, 3);
  int f = 0;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = i * segments + j, b = i * segments + (j + 1) % segments;
      const int c = a + segments, d = b + segments;
      mesh.faces.row(f++) << a, b, d;
      mesh.faces.row(f++) << a, d, c;
    }
  return mesh;
}

// A closed cone (apex at `apex`, base fan at the centre of its base circle).
Mesh ClosedCone(const Eigen::Vector3d& apex, double direction) {
  const int segments = 6;
  Mesh mesh;
  mesh.vertices.resize(segments + 2, 3);
  mesh.vertices.row(0) = apex.transpose();
  mesh.vertices.row(1) = (apex + Eigen::Vector3d(0, 0, direction)).transpose();
  for (int j = 0; j < segments; ++j) {
    const double theta = 2 * M_PI * j / segments;
    mesh.vertices.row(2 + j) = (apex + Eigen::Vector3d(std::cos(theta), std::sin(theta), direction)).transpose();
  }
  mesh.faces.resize(2 * segments, 3);
  for (int j = 0; j < segments; ++j) {
    mesh.faces.row(2 * j) << 0, 2 + j, 2 + (j + 1) % segments;
    mesh.faces.row(2 * j + 1) << 1, 2 + (j + 1) % segments, 2 + j;
  }
  return mesh;
}

TEST(MeshValidation, ClosedSphereIsWatertightAndClean) {
  const MeshReport report = ValidateMesh(MakeUvSphere(1.0, 8, 12));
  EXPECT_EQ(report.num_vertices, 2 + 7 * 12);
  EXPECT_EQ(report.num_faces, 2 * 12 * 7);
  EXPECT_TRUE(report.is_watertight());
  EXPECT_TRUE(report.is_clean());
  EXPECT_EQ(report.num_components, 1);
  EXPECT_EQ(report.num_boundary_loops, 0);
  EXPECT_EQ(report.num_boundary_edges, 0);
  EXPECT_TRUE(report.unreferenced_vertices.empty());
  EXPECT_EQ(report.component_of_face, std::vector<int>(report.num_faces, 0));
}

TEST(MeshValidation, OpenCylinderHasTwoBoundaryLoops) {
  const int segments = 10;
  const MeshReport report = ValidateMesh(OpenCylinder(segments));
  EXPECT_TRUE(report.is_manifold());
  EXPECT_FALSE(report.is_watertight());
  EXPECT_TRUE(report.is_clean());
  EXPECT_EQ(report.num_boundary_edges, 2 * segments);
  EXPECT_EQ(report.num_boundary_loops, 2);
  EXPECT_EQ(report.num_components, 1);
}

TEST(MeshValidation, TwoSpheresAreTwoComponents) {
  Mesh second = MakeUvSphere(0.5, 5, 7);
  second.vertices.col(0).array() += 3.0;
  const Mesh first = MakeUvSphere(1.0, 6, 6);
  const MeshReport report = ValidateMesh(Concatenate(first, second));
  EXPECT_EQ(report.num_components, 2);
  EXPECT_TRUE(report.is_watertight());
  for (int f = 0; f < report.num_faces; ++f) EXPECT_EQ(report.component_of_face[f], f < first.num_faces() ? 0 : 1);
}

TEST(MeshValidation, ThreeTrianglesOnOneEdgeIsNonManifold) {
  Mesh mesh;
  mesh.vertices.resize(5, 3);
  mesh.vertices << 0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1;
  mesh.faces.resize(3, 3);
  mesh.faces << 0, 1, 2, 1, 0, 3, 0, 1, 4;
  const MeshReport report = ValidateMesh(mesh);
  ASSERT_EQ(report.non_manifold_edges.size(), 1u);
  EXPECT_EQ(report.non_manifold_edges[0], std::make_pair(0, 1));
  EXPECT_TRUE(report.non_manifold_vertices.empty());  // the fans at 0 and 1 stay connected
  EXPECT_FALSE(report.is_manifold());
  EXPECT_FALSE(report.is_clean());
  EXPECT_EQ(report.num_boundary_edges, 6);
}

TEST(MeshValidation, BowTieVertexIsNonManifold) {
  Mesh mesh;
  mesh.vertices.resize(5, 3);
  mesh.vertices << 0, 0, 0, 1, 1, 0, -1, 1, 0, 1, -1, 0, -1, -1, 0;
  mesh.faces.resize(2, 3);
  mesh.faces << 0, 1, 2, 0, 4, 3;
  const MeshReport report = ValidateMesh(mesh);
  EXPECT_EQ(report.non_manifold_vertices, std::vector<int>{0});
  EXPECT_TRUE(report.non_manifold_edges.empty());
  EXPECT_FALSE(report.is_manifold());
  EXPECT_EQ(report.num_components, 1);
  EXPECT_EQ(report.num_boundary_edges, 6);
}

TEST(MeshValidation, TwoConesTouchingAtTheApex) {
  Mesh up = ClosedCone(Eigen::Vector3d::Zero(), 1.0);
  Mesh down = ClosedCone(Eigen::Vector3d::Zero(), -1.0);
  Mesh mesh = Concatenate(up, down);
  // Weld the second apex onto the first: one shared vertex.
  for (int f = up.num_faces(); f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh.faces(f, k) == up.num_vertices()) mesh.faces(f, k) = 0;
  const MeshReport report = ValidateMesh(mesh);
  EXPECT_TRUE(report.non_manifold_edges.empty());
  EXPECT_EQ(report.num_boundary_edges, 0);
  EXPECT_EQ(report.non_manifold_vertices, std::vector<int>{0});
  EXPECT_EQ(report.unreferenced_vertices, std::vector<int>{up.num_vertices()});
  EXPECT_EQ(report.num_components, 1);
  EXPECT_FALSE(report.is_watertight());
  // Each cone alone is fine.
  EXPECT_TRUE(ValidateMesh(up).is_watertight());
}

TEST(MeshValidation, DegenerateAndDuplicateFaces) {
  Mesh mesh = MakeBox(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  mesh.vertices.conservativeResize(10, 3);
  mesh.vertices.row(8) << 0.5, 0, 0;  // on the edge between corners 0 and 1
  mesh.vertices.row(9) << 5, 5, 5;    // used by nobody
  mesh.faces.conservativeResize(16, 3);
  mesh.faces.row(12) << 0, 0, 1;  // repeated index
  mesh.faces.row(13) << 0, 8, 1;  // collinear: zero area
  mesh.faces.row(14) << 2, 1, 0;  // same vertex set as face 0 (0 2 1), other orientation
  mesh.faces.row(15) << 0, 1, 42;  // index out of range: reported, not a crash
  const MeshReport report = ValidateMesh(mesh);
  EXPECT_EQ(report.degenerate_faces, (std::vector<int>{12, 13, 15}));
  EXPECT_EQ(report.duplicate_faces, std::vector<int>{14});
  EXPECT_EQ(report.unreferenced_vertices, std::vector<int>{9});
  EXPECT_FALSE(report.is_clean());
  EXPECT_EQ(report.component_of_face[15], 0);
  // The duplicate makes the edges of face 0 carry three faces.
  EXPECT_FALSE(report.non_manifold_edges.empty());

  MeshValidationOptions strict;
  strict.degenerate_area_m2 = 0.6;  // the box's triangles have area 0.5
  EXPECT_EQ(ValidateMesh(MakeBox(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()), strict).degenerate_faces.size(), 12u);
}

TEST(MeshValidation, InvalidVerticesAndEmptyMesh) {
  Mesh mesh = MakeUvSphere(1.0, 4, 4);
  mesh.vertices(3, 1) = std::numeric_limits<double>::quiet_NaN();
  mesh.vertices(5, 2) = std::numeric_limits<double>::infinity();
  const MeshReport report = ValidateMesh(mesh);
  EXPECT_EQ(report.invalid_vertices, (std::vector<int>{3, 5}));
  EXPECT_FALSE(report.is_clean());
  EXPECT_TRUE(report.is_manifold());

  const MeshReport empty = ValidateMesh(Mesh{});
  EXPECT_EQ(empty.num_components, 0);
  EXPECT_TRUE(empty.is_watertight());
}

TEST(MeshValidation, ToStringSummarisesTheFindings) {
  Mesh mesh;
  mesh.vertices.resize(5, 3);
  mesh.vertices << 0, 0, 0, 1, 1, 0, -1, 1, 0, 1, -1, 0, -1, -1, 0;
  mesh.faces.resize(2, 3);
  mesh.faces << 0, 1, 2, 0, 4, 3;
  const std::string text = ValidateMesh(mesh).ToString();
  EXPECT_NE(text.find("vertices: 5, faces: 2"), std::string::npos) << text;
  EXPECT_NE(text.find("non-manifold vertices: 1 (e.g. 0)"), std::string::npos) << text;
  EXPECT_NE(text.find("boundary edges: 6 in 2 loop(s)"), std::string::npos) << text;
  EXPECT_NE(text.find("manifold: no"), std::string::npos) << text;
  const std::string clean = ValidateMesh(MakeUvSphere(1, 4, 4)).ToString();
  EXPECT_NE(clean.find("watertight: yes, clean: yes"), std::string::npos) << clean;
}

}  // namespace
}  // namespace confluent
