// Capture's frame and mask readers against images written here.

#include "calib/capture.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "calib/easymocap_io.h"
#include "calib/rig_check.h"
#include "core/error.h"
#include "core/image_io.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;
using testing::TempDir;

// An image whose every pixel tells its camera, position and channel apart.
Image Pattern(int camera, int width, int height) {
  Image image(width, height, 3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) image.at<std::uint8_t>(x, y, c) = static_cast<std::uint8_t>(40 * camera + 7 * x + 3 * y + c);
  return image;
}

TEST(Capture, ReadFramesDecodesEveryAskedCameraInTheOrderAsked) {
  TempDir dir;
  Rig rig;
  for (int c = 0; c < 5; ++c) {
    rig.cameras.push_back(LookAtCamera("cam" + std::to_string(c), Eigen::Vector3d(3.0, c, 1.0), Eigen::Vector3d::Zero(),
                                       32, 24, 30.0));
    for (int frame = 0; frame < 2; ++frame)
      WriteImage(dir / ("images/cam" + std::to_string(c) + "/00000" + std::to_string(frame) + ".png"),
                 Pattern(c + 5 * frame, 32, 24));
  }
  WriteEasyMocap(rig, dir.path());
  const Capture capture = Capture::Open(dir.path());
  const std::vector<int> asked = {4, 0, 2};
  const std::vector<Image> frames = capture.ReadFrames(asked, 1, 2);
  ASSERT_EQ(frames.size(), asked.size());
  for (std::size_t i = 0; i < asked.size(); ++i) EXPECT_EQ(frames[i].data, Pattern(asked[i] + 5, 32, 24).data) << i;
  EXPECT_THROW(capture.ReadFrames(asked, 2, 2), InputError);  // past the last frame
}

TEST(ReadMaskFile, TheFirstChannelThresholdedAtHalfRangeWhateverTheFileHolds) {
  TempDir dir;
  const int width = 300, height = 2;
  // Row 0 rises through the whole 8-bit range, row 1 falls; the other channels say the opposite.
  auto level = [&](int x, int y) { return static_cast<double>(y == 0 ? x : width - 1 - x) / (width - 1); };
  for (const int channels : {1, 2, 3, 4})
    for (const PixelType type : {PixelType::kUInt8, PixelType::kUInt16}) {
      Image image(width, height, channels, type);
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
          for (int c = 0; c < channels; ++c) {
            const double value = c == 0 ? level(x, y) : 1.0 - level(x, y);
            if (type == PixelType::kUInt8) image.at<std::uint8_t>(x, y, c) = static_cast<std::uint8_t>(std::lround(255 * value));
            else image.at<std::uint16_t>(x, y, c) = static_cast<std::uint16_t>(std::lround(65535 * value));
          }
      const std::string path = dir / ("mask_" + std::to_string(channels) + "_" + std::to_string(static_cast<int>(type)) + ".png");
      WriteImage(path, image);
      const Image mask = ReadMaskFile(path);
      ASSERT_EQ(mask.channels, 1);
      ASSERT_EQ(mask.width, width);
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
          EXPECT_EQ(mask.at<std::uint8_t>(x, y), level(x, y) * 255 >= 127.5 ? 255 : 0)
              << channels << " channels, x " << x << " y " << y;
    }
}

TEST(MaskIoU, CountsPixelsAtOrAboveHalfRangeInGreyAndColourMasksAlike) {
  // a: the left 60 columns of 100 (values 128..255 count, 0..127 do not); b: columns 40..99.
  Image a(100, 3, 1), b(100, 3, 1), a_rgb(100, 3, 3), b_rgb(100, 3, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 100; ++x) {
      a.at<std::uint8_t>(x, y) = x < 60 ? 128 + x : 127 - x % 100;
      b.at<std::uint8_t>(x, y) = x >= 40 ? 255 : 127;
      for (int c = 0; c < 3; ++c) {
        a_rgb.at<std::uint8_t>(x, y, c) = c == 0 ? a.at<std::uint8_t>(x, y) : 0;
        b_rgb.at<std::uint8_t>(x, y, c) = c == 0 ? b.at<std::uint8_t>(x, y) : 255;
      }
    }
  const double expected = 20.0 / 100.0;  // columns 40..59 of 0..99
  EXPECT_DOUBLE_EQ(MaskIoU(a, b), expected);
  EXPECT_DOUBLE_EQ(MaskIoU(a_rgb, b_rgb), expected);
  EXPECT_DOUBLE_EQ(MaskIoU(a, b_rgb), expected);
  EXPECT_DOUBLE_EQ(MaskIoU(Image(100, 3, 1), Image(100, 3, 1)), 1.0);  // both empty
  EXPECT_THROW(MaskIoU(a, Image(99, 3, 1)), UsageError);
}

}  // namespace
}  // namespace confluent
