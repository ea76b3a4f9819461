// End to end: `confluent animate` on a generated bending-arm template sequence.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>

#include "core/mesh_io.h"
#include "deform/correspondences.h"
#include "deform/point_cache.h"
#include "tests/deform/test_geometry.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

class AnimateCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    template_mesh_ = testing::MakeTube(0.04, 0.6, 24, 12);
    scan_ = testing::MakeTube(0.045, 0.6, 40, 20, 0.13);
    scan_.colors.resize(scan_.num_vertices(), 3);
    for (int v = 0; v < scan_.num_vertices(); ++v)
      scan_.colors.row(v) << static_cast<float>(v % 7) / 6.0f, 0.25f, static_cast<float>(v % 3) / 2.0f;
    WriteMesh(dir_ / "scan.ply", scan_);
    for (int frame = 0; frame < kFrames; ++frame) {
      Mesh posed = template_mesh_;
      posed.vertices = testing::RotateAbove(
          template_mesh_.vertices, 0.3,
          Eigen::AngleAxisd(BendRad(frame), Eigen::Vector3d::UnitX()).toRotationMatrix());
      char name[32];
      std::snprintf(name, sizeof(name), "tmpl/pose_%03d.obj", frame);
      WriteMesh(dir_ / name, posed);
    }
    WriteCorrespondences(dir_ / "c.json",
                         testing::TubePairs(template_mesh_, scan_, {0.1, 0.2, 0.4, 0.5}, 4, 0.04, 0.3));
  }
  static double BendRad(int frame) { return frame * 0.5; }
  static constexpr int kFrames = 4;
  testing::TempDir dir_;
  Mesh template_mesh_, scan_;
};

TEST_F(AnimateCommand, WritesFramesWithColoursAndPointCache) {
  const auto result = testing::RunConfluent({"animate", "--scan", dir_ / "scan.ply", "--correspondences",
                                             dir_ / "c.json", "--template-sequence", dir_ / "tmpl", "--out",
                                             dir_ / "out", "--pc2"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  const std::vector<RowMatrixX3d> cache = ReadPointCache(dir_ / "out/scan.pc2");
  ASSERT_EQ(cache.size(), static_cast<std::size_t>(kFrames));
  EXPECT_TRUE(std::filesystem::exists(dir_ / "out/rest.ply"));
  for (int frame = 0; frame < kFrames; ++frame) {
    char name[32];
    std::snprintf(name, sizeof(name), "out/%06d.ply", frame);
    const Mesh out = ReadMesh(dir_ / name);
    ASSERT_EQ(out.num_vertices(), scan_.num_vertices());
    ASSERT_TRUE(out.has_colors());
    EXPECT_LT((out.colors - scan_.colors).cwiseAbs().maxCoeff(), 1.0f / 255.0f);
    EXPECT_EQ(out.faces, scan_.faces);
    EXPECT_LT((out.vertices - cache[frame]).cwiseAbs().maxCoeff(), 1e-5);
    // Elbow angle of the scan follows the template's.
    const Eigen::Vector3d upper = testing::SliceCentre(scan_.vertices, out.vertices, 0.14, 0.16) -
                                  testing::SliceCentre(scan_.vertices, out.vertices, 0.04, 0.06);
    const Eigen::Vector3d lower = testing::SliceCentre(scan_.vertices, out.vertices, 0.54, 0.56) -
                                  testing::SliceCentre(scan_.vertices, out.vertices, 0.44, 0.46);
    EXPECT_NEAR(testing::AngleDeg(upper, lower), BendRad(frame) * 180 / M_PI, 2.0) << "frame " << frame;
  }
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out/000004.ply"));
}

// The singularity handlings agree away from 180 degrees (this bend stays well below it).
TEST_F(AnimateCommand, SingularityModesAgreeAwayFromTheSingularity) {
  for (const std::string mode : {"slerp", "none"}) {
    const auto result = testing::RunConfluent({"animate", "--scan", dir_ / "scan.ply", "--correspondences",
                                               dir_ / "c.json", "--template-sequence", dir_ / "tmpl", "--out",
                                               dir_ / ("out_" + mode), "--singularities", mode});
    ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  }
  const auto reference = testing::RunConfluent({"animate", "--scan", dir_ / "scan.ply", "--correspondences",
                                                dir_ / "c.json", "--template-sequence", dir_ / "tmpl", "--out",
                                                dir_ / "out"});
  ASSERT_EQ(reference.exit_code, 0) << reference.stderr_text;
  for (const std::string mode : {"slerp", "none"}) {
    const Mesh a = ReadMesh(dir_ / "out/000003.ply"), b = ReadMesh(dir_ / ("out_" + mode + "/000003.ply"));
    EXPECT_LT((a.vertices - b.vertices).cwiseAbs().maxCoeff(), 1e-6) << mode;
  }
  const auto usage = testing::RunConfluent({"animate", "--scan", dir_ / "scan.ply", "--correspondences",
                                            dir_ / "c.json", "--template-sequence", dir_ / "tmpl", "--out",
                                            dir_ / "out", "--singularities", "magic"});
  EXPECT_EQ(usage.exit_code, 2);
  EXPECT_NE(usage.stderr_text.find("--singularities"), std::string::npos) << usage.stderr_text;
}

TEST_F(AnimateCommand, BadCorrespondencesNameTheFile) {
  std::ofstream(dir_ / "bad.json") << "{\"pairs\": [{\"template_triangle\": 0, \"scan_triangle\": 123456}]}";
  const auto result = testing::RunConfluent({"animate", "--scan", dir_ / "scan.ply", "--correspondences",
                                             dir_ / "bad.json", "--template-sequence", dir_ / "tmpl", "--out",
                                             dir_ / "out"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find(dir_ / "bad.json"), std::string::npos) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("out of range"), std::string::npos) << result.stderr_text;
}

TEST_F(AnimateCommand, TopologyChangeNamesTheFrame) {
  Mesh other = testing::MakeTube(0.04, 0.6, 10, 12);
  WriteMesh(dir_ / "tmpl/pose_002.obj", other);
  const auto result = testing::RunConfluent({"animate", "--scan", dir_ / "scan.ply", "--correspondences",
                                             dir_ / "c.json", "--template-sequence", dir_ / "tmpl", "--out",
                                             dir_ / "out"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("pose_002.obj"), std::string::npos) << result.stderr_text;
  const auto usage = testing::RunConfluent({"animate", "--scan", dir_ / "scan.ply", "--correspondences",
                                            dir_ / "c.json", "--template-sequence", dir_ / "tmpl",
                                            "--reference-frame", "9", "--out", dir_ / "out"});
  EXPECT_EQ(usage.exit_code, 2);
  EXPECT_NE(usage.stderr_text.find("--reference-frame"), std::string::npos) << usage.stderr_text;
}

}  // namespace
}  // namespace confluent
