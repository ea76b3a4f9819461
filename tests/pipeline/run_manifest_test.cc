#include "pipeline/run_manifest.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "pipeline/finished_run.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

RunManifest Example() {
  RunManifest manifest;
  manifest.version = "1.2.3";
  manifest.capture = "/data/capture";
  manifest.scan = "/data/capture/scan.ply";
  manifest.masks = "/data/masks";
  manifest.held_out_cameras = {"holdout0", "holdout1"};
  manifest.frames = {4, 20};
  manifest.fps = 29.97;
  manifest.options["threads"] = {"2"};
  manifest.input_checksums = {{"scan", "0123456789abcdef"}, {"frames", 30}};
  return manifest;
}

TEST(RunManifest, RoundTripsEveryField) {
  testing::TempDir dir;
  const std::string path = dir / "run.json";
  WriteRunManifest(path, Example());
  const RunManifest read = ReadRunManifest(path);
  const RunManifest expected = Example();
  EXPECT_EQ(read.version, expected.version);
  EXPECT_EQ(read.capture, expected.capture);
  EXPECT_EQ(read.scan, expected.scan);
  EXPECT_EQ(read.correspondences, "automatic");
  EXPECT_EQ(read.masks, expected.masks);
  EXPECT_EQ(read.held_out_cameras, expected.held_out_cameras);
  EXPECT_EQ(read.frames.first, 4);
  EXPECT_EQ(read.frames.end, 20);
  EXPECT_DOUBLE_EQ(read.fps, 29.97);
  EXPECT_EQ(read.options, expected.options);
  EXPECT_EQ(read.input_checksums, expected.input_checksums);
  // The layout other tools read: the held-out cameras under their historical key.
  EXPECT_NE(ReadTextFile(path).find("\"excluded_cameras\""), std::string::npos);
}

// A run.json written before "fps" existed reads with fps 0; the run's rate is then assumed.
TEST(RunManifest, OlderFileWithoutFpsReadsAsUnknownRate) {
  testing::TempDir dir;
  WriteTextFile(dir / "run.json", "{\"capture\": \"/c\", \"excluded_cameras\": [\"left\"], \"frames\": [0, 3]}\n");
  const RunManifest read = ReadRunManifest(dir / "run.json");
  EXPECT_EQ(read.fps, 0.0);
  EXPECT_EQ(read.held_out_cameras, std::vector<std::string>{"left"});
  const FinishedRun run = OpenFinishedRun(dir.path(), "");
  EXPECT_EQ(run.capture_root, "/c");
  EXPECT_EQ(run.fps(), kAssumedFrameRate);
}

TEST(RunManifest, MalformedFilesAreInputErrorsNamingTheFile) {
  testing::TempDir dir;
  const std::string path = dir / "run.json";
  for (const std::string& text : {std::string("not json"), std::string("[1, 2]"),
                                  std::string("{\"excluded_cameras\": \"holdout0\"}"),
                                  std::string("{\"frames\": [5, 2]}"), std::string("{\"fps\": -1}"),
                                  std::string("{\"options\": 3}")}) {
    WriteTextFile(path, text);
    try {
      ReadRunManifest(path);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
    }
  }
  EXPECT_THROW(ReadRunManifest(dir / "absent.json"), InputError);
}

TEST(FinishedRun, CaptureComesFromTheManifestUnlessGiven) {
  testing::TempDir dir;
  EXPECT_THROW(OpenFinishedRun(dir / "absent", "/c"), InputError);
  // No run.json: the capture must be given.
  EXPECT_THROW(OpenFinishedRun(dir.path(), ""), UsageError);
  EXPECT_EQ(OpenFinishedRun(dir.path(), "/given").capture_root, "/given");
  WriteRunManifest(RunManifestPath(dir.path()), Example());
  EXPECT_EQ(OpenFinishedRun(dir.path(), "").capture_root, "/data/capture");
  EXPECT_EQ(OpenFinishedRun(dir.path(), "/given").capture_root, "/given");
  EXPECT_DOUBLE_EQ(OpenFinishedRun(dir.path(), "").fps(), 29.97);
}

TEST(FinishedRun, HeldOutCamerasDoNotTextureUnlessAskedAndThenWarn) {
  testing::TempDir dir;
  WriteRunManifest(RunManifestPath(dir.path()), Example());
  const FinishedRun run = OpenFinishedRun(dir.path(), "");
  Rig rig;
  for (const char* name : {"cam00", "holdout0", "cam01", "holdout1"}) {
    Camera camera;
    camera.name = name;
    rig.cameras.push_back(camera);
  }
  std::string warning;
  EXPECT_EQ(TexturingExclusions(run, rig, {"cam01"}, false, &warning),
            (std::vector<std::string>{"cam01", "holdout0", "holdout1"}));
  EXPECT_TRUE(warning.empty()) << warning;
  EXPECT_EQ(TexturingExclusions(run, rig, {"holdout1"}, true, &warning), std::vector<std::string>{"holdout1"});
  EXPECT_NE(warning.find("holdout0"), std::string::npos) << warning;
  EXPECT_EQ(warning.find("holdout1"), std::string::npos) << warning;  // excluded anyway: not textured
  EXPECT_THROW(TexturingExclusions(run, rig, {"cam00", "cam01"}, false, nullptr), UsageError);
  EXPECT_THROW(TexturingExclusions(run, rig, {"nosuch"}, false, nullptr), UsageError);
}

}  // namespace
}  // namespace confluent
