// The body template driven by a BVH: posing from core poses, placement at the scan's reference
// pose, and `confluent animate --bvh` end to end on the template itself as the scan.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/mesh_io.h"
#include "tests/support/bvh_fixture.h"
#include "tests/support/test_support.h"
#include "tracking/scan_registration.h"
#include "tracking/template_motion.h"

namespace confluent {
namespace {

using namespace testing::bvh_fixture;  // NOLINT
namespace fs = std::filesystem;

TEST(TemplateMotion, PosedTemplateMeshMatchesPosedMesh) {
  const BodyTemplate body(8);
  BodyShape shape = BodyShape::Uniform(1.6);
  shape.length_scale[3] = 1.1;
  TemplatePose pose;
  pose.root_translation = Vector3d(0.2, -0.1, 0.05);
  pose.root_rotation = Vector3d(0.1, -0.2, 0.7);
  for (int j = 0; j < kNumTemplateJoints; ++j)
    for (int k = 0; k < body.dofs()[j].num_dof(); ++k)
      pose.dofs[j][k] = 0.5 * (body.dofs()[j].lower[k] + body.dofs()[j].upper[k]) + 0.05 * k;
  const Mesh expected = body.PosedMesh(shape, pose);
  const Mesh got = PosedTemplateMesh(body, shape, body.ToPose(pose));
  ASSERT_EQ(got.num_vertices(), expected.num_vertices());
  EXPECT_EQ(got.faces, expected.faces);
  EXPECT_EQ(got.face_labels, expected.face_labels);
  EXPECT_LT((got.vertices - expected.vertices).cwiseAbs().maxCoeff(), 1e-12);
}

Vector3d Bone(const std::vector<Vector3d>& p, int from, int to) { return (p[to] - p[from]).normalized(); }

TEST(TemplateMotion, BvhMotionStartsAtTheReferencePose) {
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(TestFrames());
  const BodyTemplate body(8);
  const BodyShape shape = BodyShape::Uniform(1.8);
  // The scan stands at (0.5, -0.3), turned by 90 degrees: it faces -x.
  TemplatePose reference;
  reference.root_translation = Vector3d(0.5, -0.3, 0.0);
  reference.root_rotation = Vector3d(0, 0, M_PI / 2);
  TemplateBvhMotionOptions options;
  options.fps = 50.0;
  BvhRetargetResult info;
  const std::vector<Pose> poses = TemplateMotionFromBvh(body, shape, reference, dir / "m.bvh", options, &info);
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_TRUE(info.poses.empty());
  EXPECT_EQ(info.unit, "cm");
  const Skeleton skeleton = body.MakeSkeleton(shape);
  const auto ref = JointPositions(skeleton, body.ToPose(reference));
  const auto p0 = JointPositions(skeleton, poses[0]);
  EXPECT_LT((p0[kJointPelvis] - ref[kJointPelvis]).head<2>().norm(), 1e-9);
  // T-pose at frame 0: the left arm points to the actor's left, which is -y when facing -x.
  EXPECT_GT(Bone(p0, kJointLeftShoulder, kJointLeftElbow).dot(Vector3d(0, -1, 0)), 1 - 1e-9);
  // Frame 1: left upper arm down, forearm forwards (-x), left thigh 45 degrees forwards.
  const auto p1 = JointPositions(skeleton, poses[1]);
  EXPECT_GT(Bone(p1, kJointLeftShoulder, kJointLeftElbow).dot(Vector3d(0, 0, -1)), 1 - 1e-9);
  EXPECT_GT(Bone(p1, kJointLeftElbow, kJointLeftWrist).dot(Vector3d(-1, 0, 0)), 1 - 1e-9);
  EXPECT_GT(Bone(p1, kJointLeftHip, kJointLeftKnee).dot(Vector3d(-1, 0, -1).normalized()), 1 - 1e-9);
  // The BVH root moves 10 cm along its +x (the actor's left): the leg-length ratio scales it.
  EXPECT_NEAR((p1[kJointPelvis] - p0[kJointPelvis]).norm(), 0.1 * info.translation_scale * 100.0, 1e-9);
  EXPECT_GT((p1[kJointPelvis] - p0[kJointPelvis]).dot(Vector3d(0, -1, 0)), 0.0);
}

// Writes correspondences.json pairing every 3rd template triangle with the same scan triangle.
void WriteIdentityCorrespondences(const std::string& path, int num_faces) {
  std::ofstream out(path);
  out << "{\"pairs\": [";
  for (int f = 0; f < num_faces; f += 3) out << (f ? "," : "") << "{\"template_triangle\": " << f << ", \"scan_triangle\": " << f << "}";
  out << "]}\n";
}

TEST(TemplateMotion, AnimateBvhMovesTheScanAsTheBvh) {
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(TestFrames());
  const BodyTemplate body;  // the command's template (default meshing)
  ScanRegistration registration;
  registration.shape = BodyShape::Uniform(1.7);
  registration.pose.root_translation = Vector3d(0.3, 0.2, 0.0);
  // The scan: the template itself in the reference pose, with colours.
  Mesh scan = body.PosedMesh(registration.shape, registration.pose);
  scan.colors = RowMatrixX3f::Constant(scan.num_vertices(), 3, 0.5f);
  scan.colors.col(0).setConstant(0.9f);
  WriteMesh(dir / "scan.ply", scan);
  WriteIdentityCorrespondences(dir / "c.json", scan.num_faces());
  WriteTemplateRegistration(dir / "c.json", body, registration);

  const std::string out = dir / "out";
  const testing::CommandResult result =
      testing::RunConfluent({"animate", "--scan", dir / "scan.ply", "--correspondences", dir / "c.json", "--bvh",
                             dir / "m.bvh", "--fps", "50", "--out", out, "--render", "orbit", "--render-width", "64",
                             "--render-height", "48"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text << result.stdout_text;
  EXPECT_NE(result.stdout_text.find("units cm"), std::string::npos) << result.stdout_text;
  TemplateBvhMotionOptions options;
  options.fps = 50.0;
  const std::vector<Pose> poses = TemplateMotionFromBvh(body, registration.shape, registration.pose, dir / "m.bvh", options);
  ASSERT_EQ(poses.size(), 3u);
  for (int f = 0; f < 3; ++f) {
    const std::string name = out + "/00000" + std::to_string(f) + ".ply";
    ASSERT_TRUE(fs::exists(name)) << name;
    const Mesh animated = ReadMesh(name);
    ASSERT_EQ(animated.num_vertices(), scan.num_vertices());
    EXPECT_TRUE(animated.has_colors());
    // Template = scan: each rigidly moving segment is reproduced (to solver precision).
    const Mesh expected = PosedTemplateMesh(body, registration.shape, poses[f]);
    EXPECT_LT((animated.vertices - expected.vertices).rowwise().norm().maxCoeff(), 2e-3) << "frame " << f;
    EXPECT_TRUE(fs::exists(out + "/orbit/00000" + std::to_string(f) + ".png"));
  }
  EXPECT_FALSE(fs::exists(out + "/000003.ply"));
  // Without --correspondences the registration cannot be read: a clear usage error.
  const testing::CommandResult bad = testing::RunConfluent(
      {"animate", "--scan", dir / "scan.ply", "--bvh", dir / "missing.bvh", "--correspondences", dir / "c.json", "--out", out});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.stderr_text.find("missing.bvh"), std::string::npos) << bad.stderr_text;
}

}  // namespace
}  // namespace confluent
