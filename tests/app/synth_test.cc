// End to end: `confluent synth --preset tiny` writes a complete capture and ground truth.

#include <gtest/gtest.h>

#include <filesystem>

#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/mesh_validation.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

namespace fs = std::filesystem;

TEST(SynthCommand, TinyPresetWritesCaptureAndGroundTruth) {
  testing::TempDir dir;
  const std::string capture = dir / "tiny";
  const testing::CommandResult result = testing::RunConfluent({"synth", "--preset", "tiny", "--out", capture});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  const std::string gt = dir / "tiny_gt";
  for (const std::string file : {"intri.yml", "extri.yml", "scan.ply"})
    EXPECT_TRUE(fs::is_regular_file(capture + "/" + file)) << file;
  for (const std::string file : {"intri.yml", "extri.yml", "scan.ply", "joints.json", "skeleton.json", "synth.json"})
    EXPECT_TRUE(fs::is_regular_file(gt + "/" + file)) << file;
  const std::vector<std::string> cameras = {"cam00", "cam01", "cam02", "cam03", "holdout0", "holdout1"};
  for (const auto& camera : cameras) {
    const ImageInfo plate = ReadImageInfo(capture + "/background/" + camera + ".png");
    EXPECT_EQ(plate.width, 160);
    EXPECT_EQ(plate.height, 120);
    for (int f = 0; f < 10; ++f) {
      char name[16];
      std::snprintf(name, sizeof(name), "%06d.png", f);
      const ImageInfo image = ReadImageInfo(capture + "/images/" + camera + "/" + name);
      EXPECT_EQ(image.width, 160);
      EXPECT_EQ(image.channels, 3);
      const Image mask = ReadImage(gt + "/masks/" + camera + "/" + name);
      ASSERT_EQ(mask.channels, 1);
      int on = 0, other = 0;
      for (std::uint8_t v : mask.data) {
        if (v == 255) ++on;
        else if (v != 0) ++other;
      }
      EXPECT_GT(on, 200) << camera << " " << name;  // the actor is in every view
      EXPECT_EQ(other, 0);                          // binary 0/255
    }
    EXPECT_EQ(std::distance(fs::directory_iterator(capture + "/images/" + camera), fs::directory_iterator{}), 10);
  }
  EXPECT_FALSE(fs::exists(capture + "/images/cam04"));
  // The scan and every per-frame mesh share one watertight topology.
  const Mesh scan = ReadMesh(gt + "/scan.ply");
  EXPECT_TRUE(ValidateMesh(scan).is_watertight());
  EXPECT_GT(scan.num_faces(), 8000);
  for (int f = 0; f < 10; f += 3) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d.ply", f);
    const Mesh mesh = ReadMesh(gt + "/meshes/" + name);
    EXPECT_EQ(mesh.faces, scan.faces);
  }
}

TEST(SynthCommand, BadOptionsGiveAClearMessage) {
  testing::TempDir dir;
  auto result = testing::RunConfluent({"synth", "--preset", "huge", "--out", dir / "x"});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.stderr_text.find("--preset"), std::string::npos) << result.stderr_text;
  result = testing::RunConfluent({"synth", "--preset", "tiny", "--out", dir / "x", "--actor-sequence", dir / "missing"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("missing"), std::string::npos) << result.stderr_text;
}

// A rigged actor (mesh + skin.json) performs like the procedural actor it was exported from:
// the ground truth's scan.ply and skin.json fed back give the same per-frame meshes and masks.
TEST(SynthCommand, RiggedActorFromTheGroundTruthReproducesTheCapture) {
  testing::TempDir dir;
  ASSERT_EQ(testing::RunConfluent({"synth", "--preset", "tiny", "--out", dir / "a"}).exit_code, 0);
  ASSERT_TRUE(fs::is_regular_file(dir / "a_gt/skin.json"));
  const testing::CommandResult result = testing::RunConfluent(
      {"synth", "--preset", "tiny", "--out", dir / "b", "--actor-mesh", dir / "a_gt/scan.ply", "--actor-skin",
       dir / "a_gt/skin.json"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  for (const std::string frame : {"000000", "000009"}) {
    const Mesh a = ReadMesh(dir / ("a_gt/meshes/" + frame + ".ply"));
    const Mesh b = ReadMesh(dir / ("b_gt/meshes/" + frame + ".ply"));
    ASSERT_EQ(a.num_vertices(), b.num_vertices());
    EXPECT_LT((a.vertices - b.vertices).cwiseAbs().maxCoeff(), 1e-4) << frame;
    const Image mask_a = ReadImage(dir / ("a_gt/masks/cam01/" + frame + ".png"));
    const Image mask_b = ReadImage(dir / ("b_gt/masks/cam01/" + frame + ".png"));
    int differ = 0, on = 0;
    for (std::size_t i = 0; i < mask_a.data.size(); ++i) {
      differ += mask_a.data[i] != mask_b.data[i];
      on += mask_a.data[i] != 0;
    }
    EXPECT_LE(differ, on / 100 + 2) << frame;
  }
  EXPECT_TRUE(fs::is_regular_file(dir / "b_gt/joints.json"));
  // Half a rig is refused with a clear message.
  const testing::CommandResult half =
      testing::RunConfluent({"synth", "--preset", "tiny", "--out", dir / "c", "--actor-mesh", dir / "a_gt/scan.ply"});
  EXPECT_EQ(half.exit_code, 2);
  EXPECT_NE(half.stderr_text.find("--actor-skin"), std::string::npos) << half.stderr_text;
}

}  // namespace
}  // namespace confluent
