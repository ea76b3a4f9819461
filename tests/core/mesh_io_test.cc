#include "core/mesh_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "core/error.h"
#include "core/mesh_ops.h"
#include "core/mesh_validation.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;
using testing::WriteFile;

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A sphere with colours on the 1/255 grid (exact through uchar), per-vertex UVs, a texture
// and face labels.
Mesh DecoratedSphere(const std::string& texture_path) {
  Mesh mesh = MakeUvSphere(0.7, 6, 9);
  mesh.vertices.rowwise() += Eigen::RowVector3d(0.1, -2.25, 1.0 / 3.0);
  const int n = mesh.num_vertices();
  mesh.colors.resize(n, 3);
  mesh.uvs.resize(n, 2);
  for (int v = 0; v < n; ++v) {
    mesh.colors.row(v) << (v * 7 % 256) / 255.0f, (v * 13 % 256) / 255.0f, (255 - v % 256) / 255.0f;
    mesh.uvs.row(v) << (v % 9) / 9.0, std::sqrt(static_cast<double>(v)) / 10.0;
  }
  mesh.face_uvs = mesh.faces;
  mesh.texture_path = texture_path;
  for (int f = 0; f < mesh.num_faces(); ++f) mesh.face_labels.push_back(f % 16 - 3);
  return mesh;
}

void ExpectInputError(const std::string& path, const std::string& part) {
  try {
    ReadMesh(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find(part), std::string::npos) << error.what();
  }
}

TEST(MeshIo, ObjRoundTripKeepsEverythingExactly) {
  TempDir dir;
  const std::string texture = dir / "skin.png";
  WriteFile(texture, "not really a png");
  const Mesh mesh = DecoratedSphere(texture);
  const std::string path = dir / "sub/scan.obj";
  WriteMesh(path, mesh);
  EXPECT_TRUE(fs::exists(dir / "sub/scan.mtl"));
  EXPECT_NE(ReadFile(dir / "sub/scan.mtl").find("map_Kd ../skin.png"), std::string::npos);
  const Mesh back = ReadMesh(path);
  EXPECT_EQ(back.vertices, mesh.vertices);  // shortest round-trip text: bit exact
  EXPECT_EQ(back.faces, mesh.faces);
  ASSERT_TRUE(back.has_colors());
  EXPECT_EQ(back.colors, mesh.colors);
  ASSERT_TRUE(back.has_uvs());
  EXPECT_EQ(back.uvs, mesh.uvs);
  EXPECT_EQ(back.face_uvs, mesh.face_uvs);
  EXPECT_EQ(back.texture_path, fs::absolute(texture).lexically_normal().string());
  EXPECT_FALSE(back.has_face_labels());  // OBJ has no labels
}

TEST(MeshIo, ObjWithoutOptionalDataHasNoneBack) {
  TempDir dir;
  const Mesh mesh = MakeBox(Eigen::Vector3d(-1, -2, -3), Eigen::Vector3d(1, 2, 3));
  WriteMesh(dir / "box.obj", mesh);
  EXPECT_FALSE(fs::exists(dir / "box.mtl"));
  const Mesh back = ReadMesh(dir / "box.obj");
  EXPECT_EQ(back.vertices, mesh.vertices);
  EXPECT_EQ(back.faces, mesh.faces);
  EXPECT_FALSE(back.has_colors());
  EXPECT_FALSE(back.has_uvs());
  EXPECT_TRUE(back.texture_path.empty());
}

void ExpectPlyRoundTrip(bool binary) {
  TempDir dir;
  const Mesh mesh = DecoratedSphere(dir / "tex/skin.jpg");
  MeshWriteOptions options;
  options.binary = binary;
  options.double_precision = true;
  WriteMesh(dir / "scan.ply", mesh, options);
  EXPECT_EQ(ReadFile(dir / "scan.ply").find(binary ? "format binary_little_endian" : "format ascii"), 4u);
  const Mesh back = ReadMesh(dir / "scan.ply");
  EXPECT_EQ(back.vertices, mesh.vertices);
  EXPECT_EQ(back.faces, mesh.faces);
  ASSERT_TRUE(back.has_colors());
  EXPECT_LT((back.colors - mesh.colors).cwiseAbs().maxCoeff(), 1e-7f);
  EXPECT_EQ(back.face_labels, mesh.face_labels);
  ASSERT_TRUE(back.has_uvs());  // per-corner "texcoord" lists
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR((back.uvs.row(back.face_uvs(f, k)) - mesh.uvs.row(mesh.face_uvs(f, k))).norm(), 0.0, 1e-7);
  EXPECT_EQ(back.texture_path, mesh.texture_path);

  // Default float precision: within float rounding; optional data can be switched off.
  options.double_precision = false;
  options.write_colors = false;
  options.write_face_labels = false;
  WriteMesh(dir / "plain.ply", mesh, options);
  const Mesh plain = ReadMesh(dir / "plain.ply");
  EXPECT_LT((plain.vertices - mesh.vertices).cwiseAbs().maxCoeff(), 3e-7);
  EXPECT_FALSE(plain.has_colors());
  EXPECT_FALSE(plain.has_face_labels());
}

TEST(MeshIo, PlyBinaryRoundTrip) { ExpectPlyRoundTrip(true); }
TEST(MeshIo, PlyAsciiRoundTrip) { ExpectPlyRoundTrip(false); }

TEST(MeshIo, WriteOverwritesAtomicallyAndLeavesNoTemporaries) {
  TempDir dir;
  WriteMesh(dir / "a.ply", MakeBox(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()));
  WriteMesh(dir / "a.ply", MakeUvSphere(1.0, 4, 5));
  EXPECT_EQ(ReadMesh(dir / "a.ply").num_vertices(), 2 + 3 * 5);
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir.path())) files += entry.is_regular_file();
  EXPECT_EQ(files, 1);
  EXPECT_THROW(WriteMesh(dir / "a.stl", MakeUvSphere(1.0, 4, 5)), OutputError);
}

TEST(MeshIo, ObjPolygonsAreFanTriangulated) {
  TempDir dir;
  WriteFile(dir / "poly.obj",
            "# a quad and a pentagon\n"
            "o thing\ng part\ns off\n"
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 3 0.5 0\r\nv 2 1 0\n"
            "usemtl none\n"
            "f 1 2 3 4 # a trailing comment\n"
            "f  2 5 6 7 3 \n");
  const Mesh mesh = ReadMesh(dir / "poly.obj");
  ASSERT_EQ(mesh.num_faces(), 2 + 3);
  RowMatrixX3i expected(5, 3);
  expected << 0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 6, 1, 6, 2;
  EXPECT_EQ(mesh.faces, expected);
  EXPECT_EQ(mesh.num_vertices(), 7);
}

TEST(MeshIo, ObjAllIndexFormsAndNegativeIndices) {
  TempDir dir;
  WriteFile(dir / "forms.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
            "vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n"
            "vn 0 0 1\n"
            "f 1/1 2/2 3/3\n"
            "f 2/2/1 4/4/1 3/3/1\n"
            "f -4/-4 -3/-3 -2/-2\n"
            "f -3/-3/-1 -1/-1/-1 -2/-2/-1\n");
  const Mesh mesh = ReadMesh(dir / "forms.obj");
  RowMatrixX3i expected(4, 3);
  expected << 0, 1, 2, 1, 3, 2, 0, 1, 2, 1, 3, 2;
  EXPECT_EQ(mesh.faces, expected);
  ASSERT_TRUE(mesh.has_uvs());
  EXPECT_EQ(mesh.face_uvs, expected);
  EXPECT_EQ(mesh.uvs.row(3), Eigen::RowVector2d(1, 1));

  WriteFile(dir / "normals.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf -3//-1 -2//-1 -1//-1\n");
  const Mesh plain = ReadMesh(dir / "normals.obj");
  EXPECT_EQ(plain.num_faces(), 2);
  EXPECT_EQ(plain.faces.row(1), Eigen::RowVector3i(0, 1, 2));
  EXPECT_FALSE(plain.has_uvs());
}

TEST(MeshIo, ObjVertexColoursAndHomogeneousW) {
  TempDir dir;
  WriteFile(dir / "c.obj", "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 0.5\nf 1 2 3\n");
  const Mesh colored = ReadMesh(dir / "c.obj");
  ASSERT_TRUE(colored.has_colors());
  EXPECT_EQ(colored.colors.row(2), Eigen::RowVector3f(0, 0, 0.5f));
  WriteFile(dir / "w.obj", "v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1\nf 1 2 3\n");
  const Mesh homogeneous = ReadMesh(dir / "w.obj");
  EXPECT_FALSE(homogeneous.has_colors());
  EXPECT_EQ(homogeneous.vertices(1, 0), 1.0);
}

TEST(MeshIo, ObjMaterialTextureIsMadeAbsolute) {
  TempDir dir;
  fs::create_directories(dir / "model/maps");
  WriteFile(dir / "model/mat.mtl",
            "newmtl other\nKd 1 0 0\nmap_Kd maps/other.png\n\n"
            "newmtl skin\nKd 1 1 1\nmap_Kd -s 1 1 1 maps/skin.png\n");
  WriteFile(dir / "model/person.obj", "mtllib mat.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl skin\nf 1 2 3\n");
  EXPECT_EQ(ReadMesh(dir / "model/person.obj").texture_path,
            fs::absolute(dir / "model/maps/skin.png").lexically_normal().string());
  // Without usemtl the first texture is used; a missing MTL just means no texture.
  WriteFile(dir / "model/first.obj", "mtllib mat.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(ReadMesh(dir / "model/first.obj").texture_path,
            fs::absolute(dir / "model/maps/other.png").lexically_normal().string());
  WriteFile(dir / "model/missing.obj", "mtllib nothere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_TRUE(ReadMesh(dir / "model/missing.obj").texture_path.empty());
}

// Little helpers for hand-made binary PLY bodies.
template <typename T>
void Put(std::string* out, T value, bool big_endian = false) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if (big_endian) std::reverse(bytes, bytes + sizeof(T));
  out->append(bytes, sizeof(T));
}

// A PLY with a foreign element and unknown properties of every kind around the known ones.
std::string ForeignPly(bool binary, bool big_endian) {
  std::string text = "ply\nformat ";
  text += !binary ? "ascii" : big_endian ? "binary_big_endian" : "binary_little_endian";
  text += " 1.0\ncomment made by hand\nobj_info nothing\n"
          "element material 1\nproperty uchar shine\nproperty list uchar double spec\n"
          "element vertex 4\nproperty short id\nproperty double x\nproperty double y\nproperty double z\n"
          "property float nx\nproperty list int ushort junk\nproperty float red\nproperty float green\n"
          "property float blue\nproperty uchar alpha\n"
          "element face 2\nproperty char flags\nproperty list int uint vertex_indices\nproperty uint label\n"
          "property double quality\n"
          "element edge 1\nproperty int vertex1\nproperty int vertex2\n"
          "end_header\n";
  const double xyz[4][3] = {{0, 0, 0}, {1.5, 0, 0}, {1.5, 2.25, 0}, {0, 2.25, -1e-3}};
  if (!binary) {
    text += "7 2 0.5 0.25\n";
    for (int v = 0; v < 4; ++v)
      text += std::to_string(v) + " " + std::to_string(xyz[v][0]) + " " + std::to_string(xyz[v][1]) + " " +
              std::to_string(xyz[v][2]) + " 0.0 " + (v == 1 ? "2 9 9" : "0") + " 0.25 0.5 " +
              std::to_string(v / 4.0) + " 255\n";
    text += "-1 4 0 1 2 3 42 0.5\n";
    text += "1 3 0 2 3 7 1.0\n";  // a triangle after the quad
    text += "0 1\n";
    return text;
  }
  const bool be = big_endian;
  Put<std::uint8_t>(&text, 7);
  Put<std::uint8_t>(&text, 2);
  Put<double>(&text, 0.5, be);
  Put<double>(&text, 0.25, be);
  for (int v = 0; v < 4; ++v) {
    Put<std::int16_t>(&text, static_cast<std::int16_t>(v), be);
    for (int k = 0; k < 3; ++k) Put<double>(&text, xyz[v][k], be);
    Put<float>(&text, 0.0f, be);
    Put<std::int32_t>(&text, v == 1 ? 2 : 0, be);
    for (int j = 0; j < (v == 1 ? 2 : 0); ++j) Put<std::uint16_t>(&text, 9, be);
    Put<float>(&text, 0.25f, be);
    Put<float>(&text, 0.5f, be);
    Put<float>(&text, v / 4.0f, be);
    Put<std::uint8_t>(&text, 255);
  }
  Put<std::int8_t>(&text, -1);
  Put<std::int32_t>(&text, 4, be);
  for (std::uint32_t i : {0u, 1u, 2u, 3u}) Put<std::uint32_t>(&text, i, be);
  Put<std::uint32_t>(&text, 42, be);
  Put<double>(&text, 0.5, be);
  Put<std::int8_t>(&text, 1);
  Put<std::int32_t>(&text, 3, be);
  for (std::uint32_t i : {0u, 2u, 3u}) Put<std::uint32_t>(&text, i, be);
  Put<std::uint32_t>(&text, 7, be);
  Put<double>(&text, 1.0, be);
  Put<std::int32_t>(&text, 0, be);
  Put<std::int32_t>(&text, 1, be);
  return text;
}

TEST(MeshIo, PlySkipsUnknownElementsAndPropertiesInEveryFormat) {
  TempDir dir;
  for (const auto& [binary, big_endian] : {std::pair{false, false}, std::pair{true, false}, std::pair{true, true}}) {
    SCOPED_TRACE(binary ? (big_endian ? "big endian" : "little endian") : "ascii");
    WriteFile(dir / "foreign.ply", ForeignPly(binary, big_endian));
    const Mesh mesh = ReadMesh(dir / "foreign.ply");
    ASSERT_EQ(mesh.num_vertices(), 4);
    EXPECT_EQ(mesh.vertices.row(2), Eigen::RowVector3d(1.5, 2.25, 0));
    EXPECT_EQ(mesh.vertices(3, 2), -1e-3);
    ASSERT_TRUE(mesh.has_colors());  // float colours are taken as they are
    EXPECT_EQ(mesh.colors.row(3), Eigen::RowVector3f(0.25f, 0.5f, 0.75f));
    RowMatrixX3i expected(3, 3);
    expected << 0, 1, 2, 0, 2, 3, 0, 2, 3;
    EXPECT_EQ(mesh.faces, expected);
    EXPECT_EQ(mesh.face_labels, (std::vector<int>{42, 42, 7}));
  }
}

TEST(MeshIo, ReadsLargeBinaryPlyQuickly) {
  // Correctness at size (speed is measured in bench/bench_mesh_io.cc).
  TempDir dir;
  const Mesh mesh = SubdivideMidpoint(SubdivideMidpoint(MakeUvSphere(1.0, 40, 60)));
  WriteMesh(dir / "big.ply", mesh);
  const Mesh back = ReadMesh(dir / "big.ply");
  EXPECT_EQ(back.faces, mesh.faces);
  EXPECT_LT((back.vertices - mesh.vertices).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(MeshIo, ReadsTheMakeHumanBaseMesh) {
  const std::string path = testing::SharedDataPath("makehuman/base.obj");
  if (path.empty()) GTEST_SKIP() << "../shared/data/makehuman/base.obj is not available";
  const Mesh mesh = ReadMesh(path);
  EXPECT_EQ(mesh.num_vertices(), 19158);  // as documented in the data README
  EXPECT_EQ(mesh.num_faces(), 2 * 18486);  // every polygon is a quad
  EXPECT_TRUE(mesh.has_uvs());
  const MeshReport report = ValidateMesh(mesh);
  EXPECT_TRUE(report.is_manifold());
  EXPECT_TRUE(report.unreferenced_vertices.empty());
}

// ---- errors: every one is an InputError whose message names the file.

TEST(MeshIoErrors, MissingFileAndUnknownExtension) {
  TempDir dir;
  ExpectInputError(dir / "nothere.ply", "no such file");
  ExpectInputError(dir / "nothere.obj", "no such file");
  WriteFile(dir / "mesh.stl", "solid x\nendsolid x\n");
  ExpectInputError(dir / "mesh.stl", "extension");
  fs::create_directories(dir / "folder.obj");
  ExpectInputError(dir / "folder.obj", "folder");
}

TEST(MeshIoErrors, ObjBadSyntaxNamesTheLine) {
  TempDir dir;
  WriteFile(dir / "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 zero\nf 1 2 3\n");
  ExpectInputError(dir / "bad.obj", "line 3");
  WriteFile(dir / "short.obj", "v 0 0\n");
  ExpectInputError(dir / "short.obj", "line 1");
  WriteFile(dir / "corner.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n");
  ExpectInputError(dir / "corner.obj", "line 4");
  WriteFile(dir / "two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n");
  ExpectInputError(dir / "two.obj", "line 3");
}

TEST(MeshIoErrors, ObjIndexOutOfRange) {
  TempDir dir;
  WriteFile(dir / "range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
  ExpectInputError(dir / "range.obj", "out of range");
  WriteFile(dir / "negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n");
  ExpectInputError(dir / "negative.obj", "out of range");
  WriteFile(dir / "zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  ExpectInputError(dir / "zero.obj", "line 4");
  WriteFile(dir / "uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/1\n");
  ExpectInputError(dir / "uv.obj", "out of range");
}

TEST(MeshIoErrors, NonFiniteCoordinates) {
  TempDir dir;
  WriteFile(dir / "nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
  ExpectInputError(dir / "nan.obj", "non-finite");
  WriteFile(dir / "inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n");
  ExpectInputError(dir / "inf.obj", "line 3");
  std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < 9; ++i) Put<float>(&ply, i == 4 ? std::numeric_limits<float>::quiet_NaN() : 1.0f);
  WriteFile(dir / "nan.ply", ply);
  ExpectInputError(dir / "nan.ply", "non-finite");
  WriteFile(dir / "inf.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                             "property float z\nend_header\n0 -inf 0\n");
  ExpectInputError(dir / "inf.ply", "non-finite");
}

TEST(MeshIoErrors, TruncatedPly) {
  TempDir dir;
  const Mesh mesh = MakeUvSphere(1.0, 8, 8);
  WriteMesh(dir / "full.ply", mesh);
  const std::string full = ReadFile(dir / "full.ply");
  for (const std::size_t cut : {full.size() - 1, full.size() - 20, full.size() / 2, full.find("end_header") + 15}) {
    WriteFile(dir / "cut.ply", full.substr(0, cut));
    ExpectInputError(dir / "cut.ply", "truncated");
  }
  // A corrupt count far beyond the file size fails fast instead of allocating gigabytes.
  std::string huge = full;
  huge.replace(huge.find("element vertex 58"), 17, "element vertex 1999999999");
  WriteFile(dir / "huge.ply", huge);
  ExpectInputError(dir / "huge.ply", "truncated");
  WriteFile(dir / "header.ply", full.substr(0, full.find("end_header")));
  ExpectInputError(dir / "header.ply", "end_header");
  MeshWriteOptions ascii;
  ascii.binary = false;
  WriteMesh(dir / "full_ascii.ply", mesh, ascii);
  const std::string text = ReadFile(dir / "full_ascii.ply");
  WriteFile(dir / "cut_ascii.ply", text.substr(0, text.size() - 10));
  ExpectInputError(dir / "cut_ascii.ply", "truncated");
}

TEST(MeshIoErrors, PlyBadHeaderBadValuesAndIndexOutOfRange) {
  TempDir dir;
  const std::string header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  WriteFile(dir / "range.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  ExpectInputError(dir / "range.ply", "out of range");
  WriteFile(dir / "negative.ply", header + "0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n");
  ExpectInputError(dir / "negative.ply", "out of range");
  WriteFile(dir / "word.ply", header + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n");
  ExpectInputError(dir / "word.ply", "line 11");
  WriteFile(dir / "magic.ply", "plx\n" + header.substr(4));
  ExpectInputError(dir / "magic.ply", "not a PLY");
  WriteFile(dir / "type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n0\n");
  ExpectInputError(dir / "type.ply", "line 4");
  WriteFile(dir / "noxyz.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n");
  ExpectInputError(dir / "noxyz.ply", "x, y or z");
  std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                       "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < 9; ++i) Put<float>(&binary, 0.5f * i);
  Put<std::uint8_t>(&binary, 3);
  for (int i : {0, 1, 1000}) Put<std::int32_t>(&binary, i);
  WriteFile(dir / "range_binary.ply", binary);
  ExpectInputError(dir / "range_binary.ply", "face 0");
}

}  // namespace
}  // namespace confluent
