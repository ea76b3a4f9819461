// End to end: `confluent render` on a small generated capture (a sphere seen by a ring of 8
// cameras) with a run whose scan/ holds the sphere for some frames.

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/mesh_ops.h"
#include "tests/app/capture_fixture.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

bool HaveFfmpeg() { return std::system("ffmpeg -version >/dev/null 2>&1 && ffprobe -version >/dev/null 2>&1") == 0; }

// A capture of 5 frames and a run with the sphere's mesh for frames 0, 1, 3, 4 (2 is missing).
struct RenderFixture {
  testing::TempDir dir;
  std::string capture = dir / "capture";
  std::string run = dir / "run";
  RenderFixture() {
    testing::FixtureOptions options;
    options.num_frames = 5;
    options.num_cameras = 8;  // 45 degrees apart: a held-out view is well covered by its neighbours
    testing::WriteFixtureCapture(capture, options);
    Mesh sphere = MakeUvSphere(options.sphere_radius_m, 24, 48);
    sphere.vertices.col(2).array() += 1.0;
    for (int frame : {0, 1, 3, 4}) {
      char name[32];
      std::snprintf(name, sizeof(name), "/scan/%06d.ply", frame);
      WriteMesh(run + name, sphere);
    }
  }
};

int CountFiles(const std::string& dir, const std::string& extension) {
  int count = 0;
  if (!fs::is_directory(dir)) return 0;
  for (const auto& entry : fs::directory_iterator(dir)) count += entry.path().extension() == extension;
  return count;
}

TEST(RenderCommand, OrbitWritesPngsAndMp4AndListsMissingFrames) {
  RenderFixture f;
  const bool mp4 = HaveFfmpeg();
  std::vector<std::string> args = {"render", f.capture, "--run", f.run, "--out", f.dir / "out", "--width", "64", "--height", "48"};
  if (mp4) args.push_back("--mp4");
  const testing::CommandResult result = testing::RunConfluent(args);
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  EXPECT_EQ(CountFiles(f.dir / "out/orbit", ".png"), 4);
  EXPECT_TRUE(fs::exists(f.dir / "out/orbit/000003.png"));
  EXPECT_FALSE(fs::exists(f.dir / "out/orbit/000002.png"));
  EXPECT_NE(result.stdout_text.find("missing scan meshes for 1 frame(s), not rendered: 2"), std::string::npos)
      << result.stdout_text;
  const Image frame = ReadImage(f.dir / "out/orbit/000000.png");
  EXPECT_EQ(frame.width, 64);
  EXPECT_EQ(frame.height, 48);
  if (!mp4) GTEST_SKIP() << "ffmpeg/ffprobe not installed: MP4 not checked";
  const std::string probe = testing::CaptureOutput("ffprobe -v error -select_streams v:0 -count_frames -show_entries "
                                    "stream=codec_name,nb_read_frames,width,height -of default=noprint_wrappers=1 '" +
                                    (f.dir / "out/orbit.mp4") + "'");
  EXPECT_NE(probe.find("codec_name=h264"), std::string::npos) << probe;
  EXPECT_NE(probe.find("nb_read_frames=4"), std::string::npos) << probe;
  EXPECT_NE(probe.find("width=64"), std::string::npos) << probe;
}

TEST(RenderCommand, FixedCameraReproducesItsImageAndBulletTimeFreezesAFrame) {
  RenderFixture f;
  // Render into cam01 while texturing only from the others: the sphere's image comes back.
  testing::CommandResult result = testing::RunConfluent({"render", f.capture, "--run", f.run, "--out", f.dir / "fixed",
                                                         "--path", "fixed:cam01", "--exclude-camera", "cam01",
                                                         "--frames", "0:2"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  const Image rendered = ReadImage(f.dir / "fixed/cam01/000001.png");
  const Image real = ReadImage(f.capture + "/images/cam01/000001.png");
  ASSERT_EQ(rendered.width, real.width);
  // The sphere centre projects to the image centre; its colour must match the real image's.
  const int cx = real.width / 2, cy = real.height / 2;
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(rendered.at<std::uint8_t>(cx, cy, c), real.at<std::uint8_t>(cx, cy, c), 20) << "channel " << c;

  result = testing::RunConfluent({"render", f.capture, "--run", f.run, "--out", f.dir / "bullet", "--path", "bullet:3",
                                  "--path-frames", "12", "--width", "48", "--height", "36"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  EXPECT_EQ(CountFiles(f.dir / "bullet/bullet_000003", ".png"), 12);

  result = testing::RunConfluent({"render", f.capture, "--run", f.run, "--out", f.dir / "path", "--path",
                                  "cameras:cam00,cam01", "--frames", "0:2", "--format", "exr"});
  ASSERT_EQ(result.exit_code, 0) << result.stderr_text;
  EXPECT_EQ(CountFiles(f.dir / "path/path", ".exr"), 2);
}

TEST(RenderCommand, BadInputFails) {
  RenderFixture f;
  testing::CommandResult result =
      testing::RunConfluent({"render", f.capture, "--run", f.run, "--out", f.dir / "o", "--path", "spiral"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.stderr_text.find("--path"), std::string::npos) << result.stderr_text;
  result = testing::RunConfluent({"render", f.capture, "--run", f.dir / "empty_run", "--out", f.dir / "o"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("scan"), std::string::npos) << result.stderr_text;
  result = testing::RunConfluent(
      {"render", f.capture, "--run", f.run, "--out", f.dir / "o", "--exclude-camera", "nosuchcamera"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.stderr_text.find("cam00"), std::string::npos) << "lists the known cameras: " << result.stderr_text;
}

}  // namespace
}  // namespace confluent
