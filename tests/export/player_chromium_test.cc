// export/player_writer.h: the embedded web player, and (the done-when of issue 22) the page in
// Debian's headless Chromium showing frame N of an export from a fixed camera, compared with
// confluent's own render (MeshRenderer, unlit, same texture and vertices) of that frame.

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "core/image_io.h"
#include "core/image_metrics.h"
#include "core/video.h"
#include "core/video_writer.h"
#include "export/gltf_writer.h"
#include "export/player_writer.h"
#include "render/renderer.h"
#include "tests/export/gltf_test_scene.h"
#include "tests/export/player_test_tools.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using testing::FindBrowser;
using testing::Iou;
using testing::RunNodeScript;
using testing::Silhouette;

std::string FileBytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream bytes;
  bytes << file.rdbuf();
  return bytes.str();
}

TEST(PlayerWriter, WritesTheEmbeddedFilesByteForByte) {
  testing::TempDir dir;
  PlayerOptions options;
  options.video_url = "../atlas.webm";
  const std::vector<std::string> written = WritePlayer(dir / "player", options);
  const std::string source = testing::SourceRoot() + "/export/player";
  const std::string three = source + "/node_modules/three";
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"index.html", source + "/index.html"},
      {"player.js", source + "/player.js"},
      {"three/three.module.min.js", three + "/build/three.module.min.js"},
      {"three/three.core.min.js", three + "/build/three.core.min.js"},
      {"three/addons/loaders/GLTFLoader.js", three + "/examples/jsm/loaders/GLTFLoader.js"},
      {"three/addons/controls/OrbitControls.js", three + "/examples/jsm/controls/OrbitControls.js"},
      {"three/addons/libs/meshopt_decoder.module.js", three + "/examples/jsm/libs/meshopt_decoder.module.js"}};
  for (const auto& [path, original] : expected) {
    EXPECT_NE(std::find(written.begin(), written.end(), path), written.end()) << path;
    const std::string bytes = FileBytes(dir / ("player/" + path));
    EXPECT_GT(bytes.size(), 1000u) << path;
    if (testing::PlayerNodeModules("three").empty() && path.rfind("three/", 0) == 0) continue;
    EXPECT_TRUE(bytes == FileBytes(original)) << path << " differs from " << original;
  }
  const std::string config = FileBytes(dir / "player/config.json");
  EXPECT_NE(config.find("\"../scene.glb\""), std::string::npos) << config;
  EXPECT_NE(config.find("\"../atlas.webm\""), std::string::npos) << config;
  options.scene_url.clear();
  EXPECT_THROW(WritePlayer(dir / "other", options), UsageError);
  Camera camera;
  camera.width = 64;
  camera.height = 48;
  camera.K << 50, 0, 31.5, 0, 51, 23.25, 0, 0, 1;
  camera.translation << 0.1, -0.2, 3.0;
  EXPECT_EQ(PlayerCameraQuery(camera, 7),
            "fx=50&fy=51&cx=31.5&cy=23.25&width=64&height=48&R=1,0,0,0,1,0,0,0,1"
            "&t=0.10000000000000001,-0.20000000000000001,3&frame=7");
  EXPECT_THROW(PlayerCameraQuery(camera, -1), UsageError);
  EXPECT_THROW(WritePlayer("/proc/confluent-no/player"), OutputError);
}

// An export in `dir`: scene.glb of the moving sphere, atlas.mp4 (H.264, one atlas per frame)
// and player/.
struct SphereExport {
  Mesh sphere = testing::TexturedSphere(24, 36);
  std::vector<RowMatrixX3d> positions;

  SphereExport(const std::string& dir, int frames) : positions(testing::SphereFrames(sphere, frames)) {
    std::vector<Image> atlases;
    for (int k = 0; k < frames; ++k) atlases.push_back(testing::SphereTexture(k));
    WriteGlb(dir + "/scene.glb", sphere, positions, atlases[0]);
    WriteVideo(dir + "/atlas.mp4", atlases);
    WritePlayer(dir + "/player");
  }
};

TEST(PlayerInChromium, FrameFromAFixedCameraMatchesConfluentsRender) {
  const testing::Browser found = FindBrowser();
  if (!found.missing.empty()) GTEST_SKIP() << found.missing;
  std::unique_ptr<MeshRenderer> renderer;
  try {
    renderer = std::make_unique<MeshRenderer>();
  } catch (const std::exception& error) {
    GTEST_SKIP() << "no EGL context for confluent's render: " << error.what();
  }
  const int shown = 3;
  testing::TempDir dir;
  const SphereExport scene(dir.path(), 6);
  const Mesh& sphere = scene.sphere;
  const std::vector<RowMatrixX3d>& positions = scene.positions;

  const Camera camera = testing::LookAtCamera(Eigen::Vector3d(0, 0.1, 0.15), Eigen::Vector3d(0.8, -1.0, 0.45));
  const std::string page = "player/index.html?" + PlayerCameraQuery(camera, shown);
  const std::string screenshot = dir / "screenshot.png";
  const std::string report =
      RunNodeScript("player_screenshot.cjs", {found.modules, found.chromium, dir.path(), page, std::to_string(camera.width),
                                              std::to_string(camera.height), screenshot, "60"});
  ASSERT_NE(report.find("\"ready\": true"), std::string::npos) << report;
  EXPECT_NE(report.find("\"frame\": " + std::to_string(shown)), std::string::npos) << report;
  const Image browser = ReadImage(screenshot);
  ASSERT_EQ(browser.width, camera.width);
  ASSERT_EQ(browser.height, camera.height);

  // confluent's render of the same frame and camera, textured with the same decoded video frame.
  // Both decode the 8-bit texture from sRGB before filtering and encode sRGB on output
  // (MeshRenderer: an sRGB texture format and srgb_output; three.js: the video texture's
  // colorSpace and the renderer's outputColorSpace), so unlit texels come out as they are.
  VideoReader video(dir / "atlas.mp4");
  const auto render = [&](int k) {
    Mesh mesh = sphere;
    mesh.vertices = positions[k];
    RenderRequest request;
    request.meshes = {renderer->AddMesh(mesh, "sphere", video.ReadFrame(k))};
    request.silhouette = true;
    request.shading.lit = false;
    request.shading.srgb_output = true;
    return renderer->Render(camera, request);
  };
  const RenderResult ours = render(shown);
  Image intersection;
  const double iou = Iou(Silhouette(browser), ours.silhouette, &intersection);
  const double psnr = MaskedPsnr(browser, ours.color, intersection);
  std::printf("player vs confluent, frame %d: silhouette IoU %.4f, PSNR inside %.2f dB\n", shown, iou, psnr);
  EXPECT_GE(iou, 0.98);
  EXPECT_GE(psnr, 28.0);
  // The frame is the one asked for: the neighbours match clearly worse.
  for (const int other : {shown - 1, shown + 1}) {
    const RenderResult theirs = render(other);
    Image other_intersection;
    const double other_iou = Iou(Silhouette(browser), theirs.silhouette, &other_intersection);
    EXPECT_LT(other_iou, iou - 0.02) << "frame " << other;
    EXPECT_LT(MaskedPsnr(browser, theirs.color, other_intersection), psnr - 3.0) << "frame " << other;
  }
  if (const char* keep = std::getenv("CONFLUENT_PLAYER_SCREENSHOT")) {  // for looking at them
    WriteImage(keep, browser);
    WriteImage(std::string(keep) + ".confluent.png", ours.color);
  }
}

// The interactive page: the mesh follows the playing video, stays on the video's frame when
// paused, and the timeline moves both.
TEST(PlayerInChromium, PlaysWithTheMeshFollowingTheVideo) {
  const testing::Browser found = FindBrowser();
  if (!found.missing.empty()) GTEST_SKIP() << found.missing;
  const int frames = 12, seek = 7;
  testing::TempDir dir;
  const SphereExport scene(dir.path(), frames);
  const std::string output = RunNodeScript(
      "player_interaction.cjs", {found.modules, found.chromium, dir.path(), "player/index.html", std::to_string(seek), "60"});
  const nlohmann::json report = nlohmann::json::parse(output.substr(std::min(output.find('{'), output.size())), nullptr, false);
  ASSERT_TRUE(report.is_object() && report.value("ok", false)) << output;
  EXPECT_GE(report["frames_seen_playing"].size(), 4u) << output;
  const nlohmann::json& paused = report["after_pause"];
  const double fps = paused["fps"];
  EXPECT_EQ(fps, 25.0);
  EXPECT_TRUE(paused["paused"].get<bool>()) << output;
  EXPECT_EQ(paused["frame"].get<int>(), static_cast<int>(std::floor(paused["time"].get<double>() * fps + 1e-3)) % frames) << output;
  const nlohmann::json& seeked = report["after_seek"];
  EXPECT_EQ(seeked["frame"].get<int>(), seek) << output;
  EXPECT_NEAR(seeked["time"].get<double>(), (seek + 0.5) / fps, 0.5 / fps) << output;
}

}  // namespace
}  // namespace confluent
