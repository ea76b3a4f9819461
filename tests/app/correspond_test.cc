// End to end: `confluent correspond` on the low-resolution studio actor (a scan with a different
// tessellation from the template) and on a sphere (refused with the fit residual).

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>

#include "core/atomic_file.h"
#include "core/body_segments.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/mesh_ops.h"
#include "deform/correspondences.h"
#include "studio/actor.h"
#include "tracking/body_template.h"
#include "tracking/motion_io.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(CorrespondCommand, WritesValidPairsRegistrationTemplateAndPicture) {
  testing::TempDir dir;
  StudioActorOptions options;
  options.target_triangles = 12000;
  const Mesh scan = BuildStudioActor(options).mesh;
  WriteMesh(dir / "scan.ply", scan);
  const auto result = testing::RunConfluent({"correspond", "--scan", dir / "scan.ply", "--out", dir / "out/c.json"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  EXPECT_NE(result.stdout_text.find("left_forearm"), std::string::npos) << result.stdout_text;
  EXPECT_NE(result.stdout_text.find("residual"), std::string::npos) << result.stdout_text;
  const Correspondences pairs = ReadCorrespondences(dir / "out/c.json");
  const Mesh template_mesh = ReadMesh(dir / "out/c_template.ply");
  ValidateCorrespondences(pairs, template_mesh.num_faces(), scan.num_faces(), dir / "out/c.json");
  EXPECT_GE(pairs.pairs.size(), 140u);
  EXPECT_LE(pairs.pairs.size(), 220u);
  std::set<std::string> segments;
  for (const CorrespondencePair& p : pairs.pairs) segments.insert(p.segment);
  EXPECT_EQ(segments.size(), static_cast<std::size_t>(kNumBodySegments));
  // The template mesh and the scan are aligned: paired triangles are close.
  double worst = 0;
  for (const CorrespondencePair& p : pairs.pairs) {
    Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      a += template_mesh.vertices.row(template_mesh.faces(p.template_triangle, k)).transpose() / 3.0;
      b += scan.vertices.row(scan.faces(p.scan_triangle, k)).transpose() / 3.0;
    }
    worst = std::max(worst, (a - b).norm());
  }
  EXPECT_LT(worst, 0.1);
  const ImageInfo picture = ReadImageInfo(dir / "out/c_pairs.png");
  EXPECT_EQ(picture.width, 1200);
  EXPECT_EQ(picture.height, 900);
  // The file carries the registration (the "template_registration" key).
  EXPECT_NE(ReadTextFile(dir / "out/c.json").find("template_registration"), std::string::npos);
}

TEST(CorrespondCommand, TemplatePoseKeepsTheTrackedShapeAndHonoursAManualPair) {
  testing::TempDir dir;
  StudioActorOptions options;
  options.target_triangles = 12000;
  const Mesh scan = BuildStudioActor(options).mesh;
  WriteMesh(dir / "scan.ply", scan);
  // A tracked reference: the generic template at rest, slightly larger (the shape is kept).
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.77);
  TrackedFrame frame;
  frame.joints = body.JointPositions(shape, frame.pose);
  WritePosesJson(dir / "poses.json", body, shape, {}, {frame}, 25.0);
  // One manual pair: the template face nearest the left wrist, with the scan face nearest to it.
  const Mesh reference = body.PosedMesh(shape, frame.pose);
  auto centroid = [](const Mesh& m, int f) {
    return Eigen::Vector3d((m.vertices.row(m.faces(f, 0)) + m.vertices.row(m.faces(f, 1)) + m.vertices.row(m.faces(f, 2))).transpose() / 3.0);
  };
  int manual_template = 0, manual_scan = 0;
  for (int f = 0; f < reference.num_faces(); ++f)
    if (reference.face_labels[f] == int(BodySegment::kLeftForearm) &&
        centroid(reference, f).y() > centroid(reference, manual_template).y())
      manual_template = f;
  for (int f = 0; f < scan.num_faces(); ++f)
    if ((centroid(scan, f) - centroid(reference, manual_template)).norm() <
        (centroid(scan, manual_scan) - centroid(reference, manual_template)).norm())
      manual_scan = f;
  Correspondences manual;
  manual.pairs.push_back({manual_template, manual_scan, "", 2.0});
  WriteCorrespondences(dir / "manual.json", manual);
  const auto result = testing::RunConfluent({"correspond", "--scan", dir / "scan.ply", "--template-pose", dir / "poses.json",
                                             "--manual", dir / "manual.json", "--out", dir / "c.json"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  const Correspondences pairs = ReadCorrespondences(dir / "c.json");
  ASSERT_GE(pairs.pairs.size(), 140u);
  EXPECT_EQ(pairs.pairs[0].template_triangle, manual_template);
  EXPECT_EQ(pairs.pairs[0].scan_triangle, manual_scan);
  EXPECT_EQ(pairs.pairs[0].segment, "left_forearm");
  EXPECT_DOUBLE_EQ(pairs.pairs[0].weight, 2.0);
  const std::string text = ReadTextFile(dir / "c.json");
  const auto registration = nlohmann::json::parse(text)["template_registration"];
  EXPECT_DOUBLE_EQ(registration["shape"]["length_scale"]["left_thigh"].get<double>(), 1.77 / 1.75);
}

TEST(CorrespondCommand, RefusesASphereWithTheResidual) {
  testing::TempDir dir;
  WriteMesh(dir / "ball.ply", MakeUvSphere(0.9, 24, 48));
  const auto result = testing::RunConfluent({"correspond", "--scan", dir / "ball.ply", "--out", dir / "c.json"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("ball.ply"), std::string::npos) << result.stderr_text;
  EXPECT_NE(result.stderr_text.find("residual"), std::string::npos) << result.stderr_text;
  EXPECT_FALSE(std::filesystem::exists(dir / "c.json"));
}

}  // namespace
}  // namespace confluent
