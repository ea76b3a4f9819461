// End to end: `confluent render` on a small generated capture (a sphere seen by a ring of 8
// cameras) with a run whose scan/ holds the sphere for some frames.

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "calib/easymocap_io.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/mesh_ops.h"
#include "pipeline/run_manifest.h"
#include "tests/app/capture_fixture.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;
using testing::CountFiles;

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

// --over-plate: the fixed view of a capture camera over its clean plate, the input colours
// matched to it. Plain-colour plates make the floor ratio (and so the gains) known exactly.
// A run that held out cam01: its fixed view of cam01 is textured from the other cameras only,
// the same image as with --exclude-camera cam01, and the capture comes from run.json. Texturing
// from the held-out camera itself needs --texture-from-held-out and warns.
TEST(RenderCommand, TheRunsHeldOutCamerasNeverTextureItsViewsUnlessAsked) {
  RenderFixture f;
  RunManifest manifest;
  manifest.capture = fs::absolute(f.capture).string();
  manifest.held_out_cameras = {"cam01"};
  manifest.frames = {0, 5};
  WriteRunManifest(RunManifestPath(f.run), manifest);
  const std::vector<std::string> view = {"--path", "fixed:cam01", "--frames", "1:2"};
  auto render = [&](std::vector<std::string> args) {
    args.insert(args.end(), view.begin(), view.end());
    const testing::CommandResult result = testing::RunConfluent(args);
    EXPECT_EQ(result.exit_code, 0) << result.stderr_text;
    return result;
  };
  const testing::CommandResult from_run = render({"render", "--run", f.run, "--out", f.dir / "from_run"});
  EXPECT_EQ(from_run.stderr_text.find("warning"), std::string::npos) << from_run.stderr_text;
  render({"render", f.capture, "--run", f.run, "--out", f.dir / "excluded", "--exclude-camera", "cam01"});
  const testing::CommandResult self =
      render({"render", "--run", f.run, "--out", f.dir / "self", "--texture-from-held-out"});
  EXPECT_NE(self.stderr_text.find("warning: texturing from camera(s) the run held out (cam01)"), std::string::npos)
      << self.stderr_text;
  const Image a = ReadImage(f.dir / "from_run/cam01/000001.png");
  const Image b = ReadImage(f.dir / "excluded/cam01/000001.png");
  const Image c = ReadImage(f.dir / "self/cam01/000001.png");
  EXPECT_EQ(a.data, b.data);
  EXPECT_NE(a.data, c.data);
}

TEST(RenderCommand, OverPlateComposesOverTheCleanPlateAndMatchesColours) {
  RenderFixture f;
  const Camera camera = ReadEasyMocap(f.capture + "/intri.yml", f.capture + "/extri.yml").Get("cam01");
  auto write_plate = [&](const std::string& name, int r, int g, int b) {
    Image plate(camera.width, camera.height, 3);
    for (std::size_t p = 0; p < plate.data.size(); p += 3) plate.data[p] = r, plate.data[p + 1] = g, plate.data[p + 2] = b;
    fs::create_directories(f.capture + "/background");
    WriteImage(f.capture + "/background/" + name + ".png", plate);
  };
  for (int c = 0; c < 8; ++c) write_plate("cam0" + std::to_string(c), 100, 120, 140);
  write_plate("cam01", 110, 120, 126);  // gains 1.1, 1.0, 0.9 from every other camera
  const std::vector<std::string> common = {"render", f.capture, "--run", f.run, "--path", "fixed:cam01",
                                           "--exclude-camera", "cam01", "--frames", "0:1"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = common;
    args.insert(args.end(), extra.begin(), extra.end());
    const testing::CommandResult result = testing::RunConfluent(args);
    EXPECT_EQ(result.exit_code, 0) << result.stderr_text;
    return result;
  };
  with({"--out", f.dir / "plain"});
  with({"--out", f.dir / "plate", "--over-plate"});
  const Image plain = ReadImage(f.dir / "plain/cam01/000000.png");
  const Image over = ReadImage(f.dir / "plate/cam01/000000.png");
  // The corner is background: black plainly, the plate's colour over the plate.
  for (int c = 0; c < 3; ++c) EXPECT_EQ(plain.at<std::uint8_t>(0, 0, c), 0);
  EXPECT_EQ(over.at<std::uint8_t>(0, 0, 0), 110);
  EXPECT_EQ(over.at<std::uint8_t>(0, 0, 1), 120);
  EXPECT_EQ(over.at<std::uint8_t>(0, 0, 2), 126);
  // The sphere's colours carry the gains.
  const int cx = plain.width / 2, cy = plain.height / 2;
  const double gains[3] = {1.1, 1.0, 0.9};
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(over.at<std::uint8_t>(cx, cy, c), std::min(255.0, gains[c] * plain.at<std::uint8_t>(cx, cy, c)), 2.0)
        << "channel " << c;

  const testing::CommandResult orbit =
      testing::RunConfluent({"render", f.capture, "--run", f.run, "--out", f.dir / "o", "--over-plate"});
  EXPECT_EQ(orbit.exit_code, 2);
  EXPECT_NE(orbit.stderr_text.find("--over-plate"), std::string::npos) << orbit.stderr_text;

  // A plate of the wrong size: a clear error naming the file.
  WriteImage(f.capture + "/background/cam01.png", Image(camera.width / 2, camera.height, 3));
  const testing::CommandResult wrong = testing::RunConfluent(
      {"render", f.capture, "--run", f.run, "--out", f.dir / "w", "--path", "fixed:cam01", "--over-plate"});
  EXPECT_EQ(wrong.exit_code, 1);
  EXPECT_NE(wrong.stderr_text.find("background/cam01.png"), std::string::npos) << wrong.stderr_text;
}

TEST(RenderCommand, BadInputFails) {
  RenderFixture f;
  testing::CommandResult result =
      testing::RunConfluent({"render", f.capture, "--run", f.run, "--out", f.dir / "o", "--path", "spiral"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.stderr_text.find("--path"), std::string::npos) << result.stderr_text;
  fs::create_directories(f.dir / "empty_run");
  result = testing::RunConfluent({"render", f.capture, "--run", f.dir / "empty_run", "--out", f.dir / "o"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("scan"), std::string::npos) << result.stderr_text;
  result = testing::RunConfluent({"render", f.capture, "--run", f.dir / "no_such_run", "--out", f.dir / "o"});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_NE(result.stderr_text.find("no_such_run: run folder not found"), std::string::npos) << result.stderr_text;
  // Without CAPTURE, the run must name one in its run.json.
  result = testing::RunConfluent({"render", "--run", f.run, "--out", f.dir / "o"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.stderr_text.find("CAPTURE: not given"), std::string::npos) << result.stderr_text;
  result = testing::RunConfluent(
      {"render", f.capture, "--run", f.run, "--out", f.dir / "o", "--exclude-camera", "nosuchcamera"});
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.stderr_text.find("cam00"), std::string::npos) << "lists the known cameras: " << result.stderr_text;
}

}  // namespace
}  // namespace confluent
