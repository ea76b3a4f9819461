#include "core/image_io.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

Image Gradient(int width, int height, int channels, PixelType type) {
  Image image(width, height, channels, type);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < channels; ++c) {
        const double value = (x * 7 + y * 13 + c * 31) % 256 / 255.0;
        if (type == PixelType::kUInt8) image.at<std::uint8_t>(x, y, c) = static_cast<std::uint8_t>(value * 255);
        if (type == PixelType::kUInt16) image.at<std::uint16_t>(x, y, c) = static_cast<std::uint16_t>(value * 65535);
        if (type == PixelType::kFloat32) image.at<float>(x, y, c) = static_cast<float>(value * 3.5 - 1.0);
      }
  return image;
}

TEST(ImageIo, LosslessFormatsRoundTripExactly) {
  testing::TempDir dir;
  struct Case { std::string name; int channels; PixelType type; };
  for (const Case& c : {Case{"rgb8.png", 3, PixelType::kUInt8}, Case{"grey8.png", 1, PixelType::kUInt8},
                        Case{"rgba16.png", 4, PixelType::kUInt16}, Case{"float.exr", 3, PixelType::kFloat32},
                        Case{"depth.exr", 1, PixelType::kFloat32}}) {
    const Image original = Gradient(37, 21, c.channels, c.type);
    WriteImage(dir / c.name, original);
    const Image loaded = ReadImage(dir / c.name);
    EXPECT_EQ(loaded.width, 37) << c.name;
    EXPECT_EQ(loaded.height, 21) << c.name;
    EXPECT_EQ(loaded.channels, c.channels) << c.name;
    EXPECT_EQ(loaded.type, c.type) << c.name;
    EXPECT_EQ(loaded.data, original.data) << c.name;
  }
}

TEST(ImageIo, JpegIsCloseAndHeaderIsReadable) {
  testing::TempDir dir;
  Image flat(64, 48, 3);
  for (auto& value : flat.data) value = 120;
  WriteImage(dir / "flat.jpg", flat);
  const Image loaded = ReadImage(dir / "flat.jpg");
  ASSERT_EQ(loaded.data.size(), flat.data.size());
  for (std::size_t i = 0; i < flat.data.size(); ++i) EXPECT_NEAR(loaded.data[i], 120, 2);
  const ImageInfo info = ReadImageInfo(dir / "flat.jpg");
  EXPECT_EQ(info.width, 64);
  EXPECT_EQ(info.height, 48);
}

TEST(ImageIo, TruncatedPngIsAnInputErrorNamingTheFile) {
  testing::TempDir dir;
  WriteImage(dir / "full.png", Gradient(200, 150, 3, PixelType::kUInt8));
  const auto size = std::filesystem::file_size(dir / "full.png");
  std::filesystem::copy_file(dir / "full.png", dir / "cut.png");
  std::filesystem::resize_file(dir / "cut.png", size / 2);
  try {
    ReadImage(dir / "cut.png");
    FAIL() << "a truncated PNG was read without error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("cut.png"), std::string::npos) << error.what();
  }
}

TEST(ImageIo, MissingAndNonImageFilesAreInputErrors) {
  testing::TempDir dir;
  EXPECT_THROW(ReadImage(dir / "absent.png"), InputError);
  std::ofstream(dir / "text.png") << "this is not a picture";
  EXPECT_THROW(ReadImage(dir / "text.png"), InputError);
  EXPECT_THROW(ReadImageInfo(dir / "text.png"), InputError);
}

// The size limit counts the pixels in the stored type: a 16-bit PNG of 100x300 RGB holds
// 180,000 bytes; with a limit of 150,000 it is refused before any pixel is decoded, naming the
// file and the size, and read whole under a limit of 200,000.
TEST(ImageIo, SizeLimitRefusesBeforeDecodingAndNamesTheFile) {
  testing::TempDir dir;
  WriteImage(dir / "deep.png", Gradient(100, 300, 3, PixelType::kUInt16));
  try {
    ReadImage(dir / "deep.png", 150000);
    FAIL() << "an image over the limit was read";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("deep.png"), std::string::npos) << message;
    EXPECT_NE(message.find("100x300"), std::string::npos) << message;
    EXPECT_NE(message.find("too large"), std::string::npos) << message;
  }
  EXPECT_EQ(ReadImage(dir / "deep.png", 200000).data, Gradient(100, 300, 3, PixelType::kUInt16).data);
}

// OpenImageIO decodes scanlines in blocks of 256 rows, so a wide image of few rows counts as
// 256 rows: 1000x2 RGB at 8 bits holds 6,000 bytes but is read through a 768,000-byte block.
TEST(ImageIo, SizeLimitCountsTheDecodersRowBlock) {
  testing::TempDir dir;
  WriteImage(dir / "strip.png", Gradient(1000, 2, 3, PixelType::kUInt8));
  EXPECT_THROW(ReadImage(dir / "strip.png", 100000), InputError);
  EXPECT_EQ(ReadImage(dir / "strip.png", 800000).width, 1000);
}

TEST(ImageIo, WriteIntoUnwritablePlaceIsOutputError) {
  testing::TempDir dir;
  std::ofstream(dir / "file") << "x";
  // A folder path that runs through a regular file cannot be created.
  EXPECT_THROW(WriteImage(dir / "file/sub/image.png", Gradient(4, 4, 3, PixelType::kUInt8)), OutputError);
}

}  // namespace
}  // namespace confluent
