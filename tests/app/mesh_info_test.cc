// End-to-end: `confluent mesh info` on generated meshes and on a broken one.

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include "core/mesh_io.h"
#include "core/mesh_ops.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using testing::RunConfluent;
using testing::TempDir;

TEST(MeshInfo, ReportsCountsBoundsAndValidation) {
  TempDir dir;
  Mesh mesh = MakeUvSphere(0.5, 6, 8);
  mesh.colors = RowMatrixX3f::Constant(mesh.num_vertices(), 3, 0.5f);
  WriteMesh(dir / "sphere.ply", mesh);
  const auto result = RunConfluent({"mesh", "info", dir / "sphere.ply", "--strict"});
  EXPECT_EQ(result.exit_code, 0) << result.stderr_text;
  const std::string& out = result.stdout_text;
  EXPECT_NE(out.find("vertices      42"), std::string::npos) << out;
  EXPECT_NE(out.find("faces         80"), std::string::npos) << out;
  EXPECT_NE(out.find("colours       yes"), std::string::npos) << out;
  EXPECT_NE(out.find("uvs           no"), std::string::npos) << out;
  EXPECT_NE(out.find("min (-0.5"), std::string::npos) << out;
  EXPECT_NE(out.find("watertight: yes"), std::string::npos) << out;
  EXPECT_NE(out.find("connected components: 1"), std::string::npos) << out;
}

TEST(MeshInfo, DefectsAreReportedAndStrictFails) {
  TempDir dir;
  Mesh mesh = MakeBox(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  mesh.faces.conservativeResize(13, 3);
  mesh.faces.row(12) = mesh.faces.row(0);  // duplicate face
  WriteMesh(dir / "box.obj", mesh);
  const auto relaxed = RunConfluent({"mesh", "info", dir / "box.obj"});
  EXPECT_EQ(relaxed.exit_code, 0) << relaxed.stderr_text;
  EXPECT_NE(relaxed.stdout_text.find("duplicate faces: 1 (e.g. 12)"), std::string::npos) << relaxed.stdout_text;
  const auto strict = RunConfluent({"mesh", "info", dir / "box.obj", "--strict"});
  EXPECT_EQ(strict.exit_code, 1);
  EXPECT_NE(strict.stderr_text.find(dir / "box.obj"), std::string::npos) << strict.stderr_text;
}

TEST(MeshInfo, TruncatedPlyFailsWithOneLineNamingTheFile) {
  TempDir dir;
  WriteMesh(dir / "full.ply", MakeUvSphere(1.0, 8, 8));
  std::ifstream in(dir / "full.ply", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(dir / "cut.ply", std::ios::binary) << bytes.substr(0, bytes.size() - 7);
  const auto result = RunConfluent({"mesh", "info", dir / "cut.ply"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find(dir / "cut.ply"), std::string::npos) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("truncated"), std::string::npos) << result.stderr_text;
  EXPECT_EQ(result.stderr_text.find('\n'), result.stderr_text.size() - 1) << result.stderr_text;

  const auto missing = RunConfluent({"mesh", "info", dir / "nothere.obj"});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.stderr_text.find("no such file"), std::string::npos) << missing.stderr_text;
}

}  // namespace
}  // namespace confluent
