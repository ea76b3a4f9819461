// End to end: `confluent synth --bvh` makes the studio actor perform a BVH file.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/mesh_io.h"
#include "tests/support/bvh_fixture.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using namespace testing::bvh_fixture;  // NOLINT
namespace fs = std::filesystem;

TEST(SynthBvh, ActorPerformsTheBvh) {
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(TestFrames());
  const std::string capture = dir / "cap";
  const testing::CommandResult result = testing::RunConfluent(
      {"synth", "--preset", "tiny", "--bvh", dir / "m.bvh", "--fps", "50", "--cameras", "2", "--heldout", "0", "--out", capture});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  // The BVH lasts 0.04 s: 3 frames at 50 fps.
  EXPECT_TRUE(fs::exists(capture + "/images/cam00/000002.png"));
  EXPECT_FALSE(fs::exists(capture + "/images/cam00/000003.png"));
  // Frame 0 is the BVH's T-pose: the left arm (the actor's left is -x) reaches ~0.9 m out; in
  // frame 1 it hangs down while the right arm stays out.
  const Mesh t_pose = ReadMesh(capture + "_gt/meshes/000000.ply");
  const Mesh arm_down = ReadMesh(capture + "_gt/meshes/000001.ply");
  EXPECT_LT(t_pose.vertices.col(0).minCoeff(), -0.8);
  EXPECT_GT(t_pose.vertices.col(0).maxCoeff(), 0.8);
  EXPECT_GT(arm_down.vertices.col(0).minCoeff(), -0.45);
  EXPECT_GT(arm_down.vertices.col(0).maxCoeff(), 0.8);
  // A BVH whose joints cannot be mapped fails with the file named.
  std::ofstream(dir / "odd.bvh") << SyntheticBvh(TestFrames(), {{"LeftArm", "bone7"}});
  const testing::CommandResult bad =
      testing::RunConfluent({"synth", "--preset", "tiny", "--bvh", dir / "odd.bvh", "--out", dir / "cap2"});
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.stderr_text.find("odd.bvh"), std::string::npos) << bad.stderr_text;
  EXPECT_NE(bad.stderr_text.find("left_shoulder"), std::string::npos) << bad.stderr_text;
}

}  // namespace
}  // namespace confluent
