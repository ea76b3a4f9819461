// export/gltf_writer.h, export/gltf_reader.h, export/seam_split.h, export/mesh_decimate.h: the
// animated scan as scene.glb, read back through meshoptimizer's decoders, and checked by the
// Khronos glTF validator.

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.h"
#include "export/gltf_format.h"
#include "export/gltf_reader.h"
#include "export/gltf_writer.h"
#include "export/mesh_decimate.h"
#include "export/seam_split.h"
#include "tests/export/gltf_test_scene.h"
#include "tests/export/player_test_tools.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using testing::SphereFrames;
using testing::SphereTexture;
using testing::TexturedSphere;
using gltf::FrameName;

// The UVs each scan vertex has at its corners.
std::vector<std::vector<Eigen::Vector2d>> CornerUvs(const Mesh& mesh) {
  std::vector<std::vector<Eigen::Vector2d>> uvs(mesh.num_vertices());
  for (int f = 0; f < mesh.num_faces(); ++f) {
    for (int c = 0; c < 3; ++c) uvs[mesh.faces(f, c)].push_back(mesh.uvs.row(mesh.face_uvs(f, c)).transpose());
  }
  return uvs;
}

double DistanceToNearest(const Eigen::Vector2d& uv, const std::vector<Eigen::Vector2d>& candidates) {
  double best = 1e9;
  for (const Eigen::Vector2d& c : candidates) best = std::min(best, (c - uv).norm());
  return best;
}

std::set<std::array<int, 3>> SortedTriangles(const RowMatrixX3i& faces, const std::vector<int>& source) {
  std::set<std::array<int, 3>> triangles;
  for (int f = 0; f < faces.rows(); ++f) {
    std::array<int, 3> t = {source[faces(f, 0)], source[faces(f, 1)], source[faces(f, 2)]};
    std::sort(t.begin(), t.end());
    triangles.insert(t);
  }
  return triangles;
}

TEST(SeamSplit, OneVertexPerDistinctUvAndTheSameTriangles) {
  const Mesh sphere = TexturedSphere();
  const SeamSplitMesh split = SplitAtUvSeams(sphere);
  EXPECT_GT(split.num_vertices(), sphere.num_vertices());  // the seam and the poles split
  EXPECT_LE(split.num_vertices(), static_cast<int>(sphere.uvs.rows()));
  ASSERT_EQ(split.num_faces(), sphere.num_faces());
  for (int f = 0; f < sphere.num_faces(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int v = split.faces(f, c);
      EXPECT_EQ(split.source_vertex[v], sphere.faces(f, c));
      EXPECT_EQ(split.uvs.row(v), sphere.uvs.row(sphere.face_uvs(f, c)));
    }
  }
  Mesh no_uvs = MakeUvSphere(1.0, 4, 6);
  EXPECT_THROW(SplitAtUvSeams(no_uvs), InputError);
}

TEST(MeshDecimate, KeepsOriginalVerticesAndLocksTheSeams) {
  const Mesh sphere = TexturedSphere(40, 60);
  const SeamSplitMesh split = SplitAtUvSeams(sphere);
  DecimateOptions options;
  options.target_triangles = 1200;
  DecimateSummary summary;
  const SeamSplitMesh decimated = DecimateSplitMesh(split, sphere.vertices, options, &summary);
  EXPECT_EQ(summary.input_triangles, sphere.num_faces());
  EXPECT_LT(decimated.num_faces(), sphere.num_faces() / 2);
  EXPECT_LE(decimated.num_faces(), 1.3 * options.target_triangles);
  EXPECT_EQ(summary.output_triangles, decimated.num_faces());
  // Kept vertices are original ones: their UV is one of their scan vertex's corner UVs.
  const auto corner_uvs = CornerUvs(sphere);
  for (int v = 0; v < decimated.num_vertices(); ++v) {
    EXPECT_LT(DistanceToNearest(decimated.uvs.row(v).transpose(), corner_uvs[decimated.source_vertex[v]]), 1e-12);
  }
  // Seam vertices (a scan vertex with two UVs) are all kept.
  std::set<int> seam, kept(decimated.source_vertex.begin(), decimated.source_vertex.end());
  std::map<int, int> uv_count;
  for (int v = 0; v < split.num_vertices(); ++v) ++uv_count[split.source_vertex[v]];
  for (const auto& [vertex, count] : uv_count) if (count > 1) seam.insert(vertex);
  for (int vertex : seam) EXPECT_TRUE(kept.count(vertex)) << "seam vertex " << vertex << " was collapsed";
  testing::ExpectCheckRefuses(DecimateOptions{0, 1.0}, "target_triangles");
}

// Every decoded vertex of every frame is its scan vertex's position to half a quantisation step.
void ExpectPositionsWithinHalfAStep(const GlbAnimation& glb, const std::vector<RowMatrixX3d>& frames, double step) {
  ASSERT_EQ(glb.positions.size(), frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) {
    for (int v = 0; v < glb.positions[k].rows(); ++v) {
      ASSERT_LE((glb.positions[k].row(v) - frames[k].row(glb.source_vertex[v])).cwiseAbs().maxCoeff(), 0.51 * step + 1e-9)
          << "frame " << k << ", vertex " << v;
    }
  }
}

// Writes, reads back, and checks positions per frame, normals and UVs within quantisation.
void ExpectRoundTrip(const GltfOptions& options) {
  const Mesh sphere = TexturedSphere();
  const std::vector<RowMatrixX3d> frames = SphereFrames(sphere, 5);
  testing::TempDir dir;
  const std::string path = dir / "scene.glb";
  const GltfSummary summary = WriteGlb(path, sphere, frames, SphereTexture(0), options);
  EXPECT_EQ(summary.frames, 5);
  EXPECT_EQ(summary.triangles, sphere.num_faces());
  const GlbAnimation glb = ReadGlb(path);
  EXPECT_EQ(glb.fps, options.fps);
  EXPECT_EQ(glb.image_mime_type, "image/jpeg");
  ASSERT_EQ(glb.positions.size(), 5u);
  ASSERT_EQ(static_cast<int>(glb.source_vertex.size()), summary.vertices);
  EXPECT_EQ(SortedTriangles(glb.faces, glb.source_vertex), SortedTriangles(sphere.faces, std::vector<int>([&] {
              std::vector<int> identity(sphere.num_vertices());
              for (int i = 0; i < sphere.num_vertices(); ++i) identity[i] = i;
              return identity;
            }())));
  EXPECT_EQ(summary.position_step_m, options.position_step_m);
  ExpectPositionsWithinHalfAStep(glb, frames, summary.position_step_m);
  Mesh topology = sphere;
  for (int k = 0; k < 5; ++k) {
    topology.vertices = frames[options.per_frame_normals ? k : 0];  // else frame 0's are shared
    const RowMatrixX3d normals = VertexNormals(topology);
    for (int v = 0; v < summary.vertices; ++v) {
      ASSERT_LT((glb.normals[k].row(v) - normals.row(glb.source_vertex[v])).norm(), 0.02) << k << " " << v;
    }
  }
  const auto corner_uvs = CornerUvs(sphere);
  for (int v = 0; v < summary.vertices; ++v) {
    EXPECT_LT(DistanceToNearest(glb.uvs.row(v).transpose(), corner_uvs[glb.source_vertex[v]]), 0.71 / 65535.0);  // 0.5 step per axis
  }
  // Corners keep their UV: every face's corners carry the UVs of the scan's face.
  std::map<std::array<int, 3>, std::array<Eigen::Vector2d, 3>> scan_face_uvs;
  for (int f = 0; f < sphere.num_faces(); ++f) {
    std::array<int, 3> key = {sphere.faces(f, 0), sphere.faces(f, 1), sphere.faces(f, 2)};
    const int r = static_cast<int>(std::min_element(key.begin(), key.end()) - key.begin());
    std::rotate(key.begin(), key.begin() + r, key.end());
    std::array<Eigen::Vector2d, 3> uv;
    for (int c = 0; c < 3; ++c) uv[c] = sphere.uvs.row(sphere.face_uvs(f, (c + r) % 3)).transpose();
    scan_face_uvs[key] = uv;
  }
  for (int f = 0; f < glb.faces.rows(); ++f) {
    std::array<int, 3> key;
    for (int c = 0; c < 3; ++c) key[c] = glb.source_vertex[glb.faces(f, c)];
    const int r = static_cast<int>(std::min_element(key.begin(), key.end()) - key.begin());
    std::rotate(key.begin(), key.begin() + r, key.end());
    ASSERT_TRUE(scan_face_uvs.count(key)) << "face " << f << " is not a scan face with the same orientation";
    for (int c = 0; c < 3; ++c) {
      EXPECT_LT((glb.uvs.row(glb.faces(f, (c + r) % 3)).transpose() - scan_face_uvs[key][c]).norm(), 1e-4);
    }
  }
}

TEST(GltfWriter, RoundTripWithMeshoptCompression) {
  GltfOptions options;
  options.fps = 30.0;
  options.position_step_m = 5e-5;
  ExpectRoundTrip(options);
}

TEST(GltfWriter, RoundTripWithSharedNormals) {
  GltfOptions options;
  options.per_frame_normals = false;
  ExpectRoundTrip(options);
}

TEST(GltfWriter, PositionStepGrowsWhenInt16CannotSpanTheFrames) {
  const Mesh sphere = TexturedSphere(4, 6);
  GltfOptions options;
  options.position_step_m = 1e-6;  // 65534 steps would span 6.5 cm; the frames span 1.3 m
  GltfSummary summary;
  const auto frames = SphereFrames(sphere, 6);
  const GlbAnimation glb = DecodeGlb(EncodeGlb(sphere, frames, SphereTexture(0, 16, 8), options, &summary));
  EXPECT_GT(summary.position_step_m, 1.5e-5);
  EXPECT_LT(summary.position_step_m, 2.5e-5);
  ExpectPositionsWithinHalfAStep(glb, frames, summary.position_step_m);
}

TEST(GltfWriter, RoundTripQuantisedWithoutCompression) {
  GltfOptions options;
  options.meshopt_compression = false;
  ExpectRoundTrip(options);
}

TEST(GltfWriter, CompressionShrinksTheFileAndIsRequired) {
  const Mesh sphere = TexturedSphere(40, 60);
  const std::vector<RowMatrixX3d> frames = SphereFrames(sphere, 4);
  GltfOptions plain;
  plain.meshopt_compression = false;
  GltfSummary compressed_summary, plain_summary;
  const auto compressed = EncodeGlb(sphere, frames, SphereTexture(0), {}, &compressed_summary);
  const auto uncompressed = EncodeGlb(sphere, frames, SphereTexture(0), plain, &plain_summary);
  EXPECT_LT(compressed.size(), 0.8 * uncompressed.size());
  const auto required = DecodeGlb(compressed).extensions_required;
  EXPECT_NE(std::find(required.begin(), required.end(), "EXT_meshopt_compression"), required.end());
  const auto plain_required = DecodeGlb(uncompressed).extensions_required;
  EXPECT_EQ(std::find(plain_required.begin(), plain_required.end(), "EXT_meshopt_compression"), plain_required.end());
}

TEST(GltfWriter, DecimatedVariantAnimatesFromTheFullMeshPositions) {
  const Mesh sphere = TexturedSphere(40, 60);
  const std::vector<RowMatrixX3d> frames = SphereFrames(sphere, 3);
  GltfOptions options;
  options.decimate_triangles = 1000;
  GltfSummary summary;
  const GlbAnimation glb = DecodeGlb(EncodeGlb(sphere, frames, SphereTexture(0), options, &summary));
  EXPECT_LT(summary.triangles, sphere.num_faces() / 2);
  EXPECT_EQ(glb.faces.rows(), summary.triangles);
  ExpectPositionsWithinHalfAStep(glb, frames, summary.position_step_m);
}

TEST(GltfWriter, UvsOutsideTheUnitSquareStayFloat) {
  Mesh sphere = TexturedSphere(6, 8);
  sphere.uvs = sphere.uvs * 2.0 - RowMatrixX2d::Constant(sphere.uvs.rows(), 2, 0.25);  // tiled: [-0.25, 1.75]
  const GlbAnimation glb = DecodeGlb(EncodeGlb(sphere, SphereFrames(sphere, 2), SphereTexture(0, 16, 8)));
  const auto corner_uvs = CornerUvs(sphere);
  for (int v = 0; v < glb.uvs.rows(); ++v) {
    EXPECT_LT(DistanceToNearest(glb.uvs.row(v).transpose(), corner_uvs[glb.source_vertex[v]]), 1e-6);
  }
}

TEST(GltfWriter, RefusesBadInputs) {
  const Mesh sphere = TexturedSphere(4, 6);
  std::vector<RowMatrixX3d> frames = SphereFrames(sphere, 2);
  const Image texture = SphereTexture(0, 16, 8);
  EXPECT_THROW(EncodeGlb(sphere, {}, texture), InputError);
  std::vector<RowMatrixX3d> short_frames = frames;
  short_frames[1].conservativeResize(3, 3);
  EXPECT_THROW(EncodeGlb(sphere, short_frames, texture), InputError);
  frames[1](0, 0) = std::nan("");
  EXPECT_THROW(EncodeGlb(sphere, frames, texture), InputError);
  EXPECT_THROW(EncodeGlb(MakeUvSphere(0.5, 4, 6), SphereFrames(sphere, 1), texture), InputError);
  EXPECT_THROW(EncodeGlb(sphere, SphereFrames(sphere, 1), Image()), InputError);
  GltfOptions options;
  options.fps = 0.0;
  testing::ExpectCheckRefuses(options, "fps");
  options = {};
  options.jpeg_quality = 0;
  testing::ExpectCheckRefuses(options, "jpeg_quality");
  options = {};
  options.position_step_m = 0.0;
  testing::ExpectCheckRefuses(options, "position_step_m");
  testing::TempDir dir;
  EXPECT_THROW(WriteGlb("/proc/confluent-no/scene.glb", sphere, SphereFrames(sphere, 1), texture), OutputError);
  EXPECT_THROW(ReadGlb(dir / "missing.glb"), InputError);
  EXPECT_THROW(DecodeGlb(std::vector<std::uint8_t>(40, 7)), InputError);
}

// The Khronos validator (npm gltf-validator) on both encodings. It cannot decode
// EXT_meshopt_compression (an info message), so the uncompressed file is the one whose data it
// checks (accessor bounds, unit normals, index ranges, animation times).
TEST(GltfWriter, KhronosValidatorReportsNoErrors) {
  if (testing::ValidateGltf("").empty()) {
    GTEST_SKIP() << "node or export/player/node_modules/gltf-validator is missing (npm ci --prefix export/player)";
  }
  const Mesh sphere = TexturedSphere();
  const std::vector<RowMatrixX3d> frames = SphereFrames(sphere, 4);
  testing::TempDir dir;
  for (const bool compress : {false, true}) {
    for (const int decimate : {0, 150}) {
      GltfOptions options;
      options.meshopt_compression = compress;
      options.decimate_triangles = decimate;
      options.jpeg_texture = decimate == 0;
      const std::string path = dir / "scene.glb";
      WriteGlb(path, sphere, frames, SphereTexture(0), options);
      const std::string report = testing::ValidateGltf(path);
      EXPECT_NE(report.find("\"errors\": 0,"), std::string::npos) << report;
      EXPECT_NE(report.find("\"warnings\": 0,"), std::string::npos) << report;
      EXPECT_NE(report.find("exit=0"), std::string::npos) << report;
    }
  }
}

// Blender's glTF importer (when Blender is installed; CI does not install it) imports the
// quantised file without meshopt compression and plays it: one object per frame, exactly one
// visible at each Blender frame, standing upright (Z up). Blender 3.4's importer cannot read
// EXT_meshopt_compression, hence GltfOptions::meshopt_compression = false for Blender.
TEST(GltfWriter, BlenderImportsAndPlaysTheUncompressedFile) {
  if (std::system("blender --version >/dev/null 2>&1") != 0) GTEST_SKIP() << "blender is not installed";
  const Mesh sphere = TexturedSphere();
  const std::vector<RowMatrixX3d> frames = SphereFrames(sphere, 4);
  testing::TempDir dir;
  const auto import = [&](bool compress) {
    GltfOptions options;
    options.meshopt_compression = compress;
    WriteGlb(dir / "scene.glb", sphere, frames, SphereTexture(0), options);
    const std::string output = testing::CaptureOutput("blender -b --factory-startup --python '" + testing::SourceRoot() +
                                                      "/tests/export/gltf_blender_check.py' -- '" + (dir / "scene.glb") +
                                                      "' 25 2>&1");
    const std::size_t line = output.rfind("\n{");  // the report's line
    const std::string text = line == std::string::npos ? "" : output.substr(line + 1, output.find('\n', line + 1) - line - 1);
    const nlohmann::json report = nlohmann::json::parse(text, nullptr, false);
    EXPECT_TRUE(report.is_object()) << output;
    return report.is_object() ? report : nlohmann::json::object();
  };
  const nlohmann::json plain = import(false);
  ASSERT_TRUE(plain.contains("import")) << plain.dump();
  ASSERT_EQ(plain["frames"].size(), 4u) << plain.dump();
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(plain["visible"][k], nlohmann::json::array({FrameName(k)})) << plain.dump();
    EXPECT_EQ(plain["uv_layers"][k], 1);
  }
  const Eigen::Vector3d lo = frames[0].colwise().minCoeff(), hi = frames[0].colwise().maxCoeff();
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(plain["frame0_min"][a].get<double>(), lo[a], 1e-3) << plain.dump();
    EXPECT_NEAR(plain["frame0_max"][a].get<double>(), hi[a], 1e-3) << plain.dump();
  }
  const nlohmann::json compressed = import(true);
  EXPECT_NE(compressed.value("import_error", "").find("EXT_meshopt_compression"), std::string::npos) << compressed.dump();
}

}  // namespace
}  // namespace confluent
