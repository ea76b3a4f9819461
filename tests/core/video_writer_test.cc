#include "core/video_writer.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <string>

#include "core/error.h"
#include "core/video.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

bool HaveFfprobe() { return std::system("ffprobe -version >/dev/null 2>&1") == 0; }

// Frame k: flat grey 20*k with a red square in the top-left corner.
Image TestFrame(int width, int height, int k) {
  Image frame(width, height, 3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) frame.at<std::uint8_t>(x, y, c) = static_cast<std::uint8_t>(20 * k);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      frame.at<std::uint8_t>(x, y, 0) = 255;
      frame.at<std::uint8_t>(x, y, 1) = 0;
      frame.at<std::uint8_t>(x, y, 2) = 0;
    }
  return frame;
}

TEST(VideoWriter, WritesH264Mp4WithExpectedFramesAndDuration) {
  if (!FfmpegAvailable()) GTEST_SKIP() << "ffmpeg is not installed";
  if (!HaveFfprobe()) GTEST_SKIP() << "ffprobe is not installed";
  testing::TempDir dir;
  const std::string path = dir / "out/clip.mp4";
  VideoWriterOptions options;
  options.fps = 10.0;
  VideoWriter writer(path, 64, 48, options);
  for (int k = 0; k < 10; ++k) writer.Write(TestFrame(64, 48, k));
  EXPECT_FALSE(std::filesystem::exists(path)) << "the final name appears only on Close()";
  writer.Close();
  ASSERT_TRUE(std::filesystem::exists(path));
  EXPECT_EQ(writer.frames_written(), 10);

  const std::string probe = testing::CaptureOutput(
      "ffprobe -v error -select_streams v:0 -count_frames -show_entries "
      "stream=codec_name,pix_fmt,width,height,nb_read_frames -of default=noprint_wrappers=1 '" + path + "'");
  EXPECT_NE(probe.find("codec_name=h264"), std::string::npos) << probe;
  EXPECT_NE(probe.find("pix_fmt=yuv420p"), std::string::npos) << probe;
  EXPECT_NE(probe.find("width=64"), std::string::npos) << probe;
  EXPECT_NE(probe.find("height=48"), std::string::npos) << probe;
  EXPECT_NE(probe.find("nb_read_frames=10"), std::string::npos) << probe;
  const double duration =
      std::atof(testing::CaptureOutput("ffprobe -v error -show_entries format=duration -of csv=p=0 '" + path + "'").c_str());
  EXPECT_NEAR(duration, 1.0, 0.05);

  // Decoded content: frame 5 is grey 100 with red in the corner (lossy, so within a few levels).
  VideoReader reader(path);
  const Image frame = reader.ReadFrame(5);
  EXPECT_NEAR(frame.at<std::uint8_t>(40, 30, 1), 100, 4);
  EXPECT_GT(frame.at<std::uint8_t>(4, 4, 0), 200);
  EXPECT_LT(frame.at<std::uint8_t>(4, 4, 1), 50);
}

TEST(VideoWriter, TwoVideosWrittenAtOnceEachCloseWhileTheOtherIsOpen) {
  if (!FfmpegAvailable()) GTEST_SKIP() << "ffmpeg is not installed";
  testing::TempDir dir;
  VideoWriter first(dir / "first.mp4", 64, 48);
  VideoWriter second(dir / "second.mp4", 32, 32);
  for (int k = 0; k < 3; ++k) {
    first.Write(TestFrame(64, 48, k));
    second.Write(TestFrame(32, 32, k));
  }
  // The second ffmpeg once inherited the first one's input socket, so closing the first waited
  // for ever. A hang here fails the test after a minute instead of blocking the suite.
  std::future<void> closing = std::async(std::launch::async, [&] { first.Close(); });
  if (closing.wait_for(std::chrono::seconds(60)) != std::future_status::ready) {
    ADD_FAILURE() << "closing the first video hangs while the second is open";
    std::fflush(nullptr);
    std::_Exit(1);
  }
  closing.get();
  EXPECT_EQ(VideoReader(dir / "first.mp4").num_frames(), 3);
  second.Close();
  EXPECT_EQ(VideoReader(dir / "second.mp4").num_frames(), 3);
}

TEST(VideoWriter, OddSizeIsPaddedAndGreyIsAccepted) {
  if (!FfmpegAvailable() || !HaveFfprobe()) GTEST_SKIP() << "ffmpeg/ffprobe are not installed";
  testing::TempDir dir;
  const std::string path = dir / "odd.mp4";
  std::vector<Image> frames;
  for (int k = 0; k < 3; ++k) {
    Image grey(33, 21, 1);
    std::fill(grey.data.begin(), grey.data.end(), static_cast<std::uint8_t>(50 * k));
    frames.push_back(grey);
  }
  WriteVideo(path, frames);
  const std::string probe = testing::CaptureOutput(
      "ffprobe -v error -select_streams v:0 -count_frames -show_entries stream=width,height,nb_read_frames "
      "-of default=noprint_wrappers=1 '" + path + "'");
  EXPECT_NE(probe.find("width=34"), std::string::npos) << probe;
  EXPECT_NE(probe.find("height=22"), std::string::npos) << probe;
  EXPECT_NE(probe.find("nb_read_frames=3"), std::string::npos) << probe;
}

TEST(VideoWriter, WrongFrameSizeIsUsageError) {
  if (!FfmpegAvailable()) GTEST_SKIP() << "ffmpeg is not installed";
  testing::TempDir dir;
  VideoWriter writer(dir / "a.mp4", 32, 32);
  EXPECT_THROW(writer.Write(Image(16, 32, 3)), UsageError);
  EXPECT_THROW(writer.Write(Image(32, 32, 3, PixelType::kFloat32)), UsageError);
  EXPECT_THROW(VideoWriter(dir / "b.mp4", 0, 10), UsageError);
}

TEST(VideoWriter, MissingFfmpegIsOutputErrorNamingTheFile) {
  testing::TempDir dir;
  VideoWriterOptions options;
  options.ffmpeg = "/nonexistent/ffmpeg-for-confluent-test";
  const char* saved = std::getenv("CONFLUENT_FFMPEG");
  if (saved != nullptr) GTEST_SKIP() << "$CONFLUENT_FFMPEG is set";
  EXPECT_FALSE(FfmpegAvailable(options));
  try {
    VideoWriter writer(dir / "c.mp4", 32, 32, options);
    writer.Write(Image(32, 32, 3));
    writer.Close();
    FAIL() << "expected OutputError";
  } catch (const OutputError& error) {
    EXPECT_NE(std::string(error.what()).find("c.mp4"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("ffmpeg"), std::string::npos) << error.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "c.mp4"));
}

TEST(VideoWriter, NoFramesIsOutputErrorAndLeavesNoFile) {
  if (!FfmpegAvailable()) GTEST_SKIP() << "ffmpeg is not installed";
  testing::TempDir dir;
  VideoWriter writer(dir / "empty.mp4", 32, 32);
  EXPECT_THROW(writer.Close(), OutputError);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
}  // namespace confluent
