#include "core/video.h"

#include <gtest/gtest.h>

#include <opencv2/videoio.hpp>

#include "core/error.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

// Writes a lossless-ish MJPG video whose frame k is a flat grey of level 10*k (+ red square).
void WriteTestVideo(const std::string& path, int frames) {
  cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25, cv::Size(64, 48));
  ASSERT_TRUE(writer.isOpened());
  for (int k = 0; k < frames; ++k) {
    cv::Mat frame(48, 64, CV_8UC3, cv::Scalar(10 * k, 10 * k, 10 * k));
    frame(cv::Rect(0, 0, 16, 16)).setTo(cv::Scalar(0, 0, 255));  // BGR red
    writer.write(frame);
  }
}

TEST(VideoReader, CountsSeeksAndConvertsToRgb) {
  testing::TempDir dir;
  WriteTestVideo(dir / "clip.avi", 12);
  VideoReader reader(dir / "clip.avi");
  EXPECT_EQ(reader.num_frames(), 12);
  EXPECT_EQ(reader.width(), 64);
  EXPECT_EQ(reader.height(), 48);
  for (int k : {3, 7, 2, 11}) {  // forward and backward seeks
    const Image frame = reader.ReadFrame(k);
    EXPECT_NEAR(frame.at<std::uint8_t>(40, 30, 1), 10 * k, 4) << "frame " << k;
    EXPECT_GT(frame.at<std::uint8_t>(4, 4, 0), 200) << "red must be channel 0 (RGB order)";
    EXPECT_LT(frame.at<std::uint8_t>(4, 4, 2), 60);
  }
  EXPECT_THROW(reader.ReadFrame(12), InputError);
}

TEST(VideoReader, MissingOrCorruptVideoIsInputError) {
  testing::TempDir dir;
  EXPECT_THROW(VideoReader(dir / "none.mp4"), InputError);
  FILE* file = std::fopen((dir / "junk.mp4").c_str(), "w");
  std::fputs("not a video at all", file);
  std::fclose(file);
  try {
    VideoReader reader(dir / "junk.mp4");
    EXPECT_EQ(reader.num_frames(), 0);
    EXPECT_THROW(reader.ReadFrame(0), InputError);
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("junk.mp4"), std::string::npos);
  }
}

}  // namespace
}  // namespace confluent
