#include "core/image_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

namespace confluent {
namespace {

Image Constant(int w, int h, std::uint8_t value) {
  Image image(w, h, 3);
  std::fill(image.data.begin(), image.data.end(), value);
  return image;
}

Image Noise(int w, int h, unsigned seed) {
  Image image(w, h, 3);
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(0, 255);
  for (auto& v : image.data) v = static_cast<std::uint8_t>(value(rng));
  return image;
}

TEST(MaskedPsnrTest, KnownErrorGivesKnownDecibels) {
  // Every compared value differs by 10 grey levels: MSE = (10/255)^2.
  const Image a = Constant(32, 24, 100), b = Constant(32, 24, 110);
  EXPECT_NEAR(MaskedPsnr(a, b), -20.0 * std::log10(10.0 / 255.0), 1e-9);
  EXPECT_DOUBLE_EQ(MaskedPsnr(a, a), kMaxPsnrDb);
}

TEST(MaskedPsnrTest, OnlyMaskedPixelsCount) {
  Image a = Constant(20, 10, 50), b = Constant(20, 10, 50);
  Image mask(20, 10, 1);
  // Left half masked and equal; right half differs wildly but is outside the mask.
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 20; ++x) {
      if (x < 10) mask.at<std::uint8_t>(x, y) = 255;
      else for (int c = 0; c < 3; ++c) b.at<std::uint8_t>(x, y, c) = 250;
    }
  EXPECT_DOUBLE_EQ(MaskedPsnr(a, b, mask), kMaxPsnrDb);
  // One masked pixel off by 51 in one channel: MSE = 0.2^2 / (100 pixels * 3 channels).
  b.at<std::uint8_t>(3, 3, 1) = 101;
  EXPECT_NEAR(MaskedPsnr(a, b, mask), -10.0 * std::log10(0.04 / 300.0), 1e-9);
}

TEST(MaskedSsimTest, IdenticalIsOneAndNoiseIsLow) {
  const Image a = Noise(64, 48, 1), b = Noise(64, 48, 2);
  EXPECT_NEAR(MaskedSsim(a, a), 1.0, 1e-9);
  EXPECT_LT(MaskedSsim(a, b), 0.1);
  // A uniform brightness offset keeps structure but lowers the luminance term only a little.
  Image brighter = a;
  for (auto& v : brighter.data) v = static_cast<std::uint8_t>(std::min(255, v + 5));
  const double ssim = MaskedSsim(a, brighter);
  EXPECT_GT(ssim, 0.9);
  EXPECT_LT(ssim, 1.0);
}

TEST(ImageMetricsTest, FloatAndByteImagesAgree) {
  const Image a8 = Noise(16, 16, 3), b8 = Noise(16, 16, 4);
  Image af(16, 16, 3, PixelType::kFloat32), bf(16, 16, 3, PixelType::kFloat32);
  for (std::size_t i = 0; i < a8.data.size(); ++i) {
    af.ptr<float>()[i] = a8.data[i] / 255.0f;
    bf.ptr<float>()[i] = b8.data[i] / 255.0f;
  }
  EXPECT_NEAR(MaskedPsnr(a8, b8), MaskedPsnr(af, bf), 1e-5);
  EXPECT_NEAR(MaskedSsim(a8, b8), MaskedSsim(af, bf), 1e-5);
}

TEST(ImageMetricsTest, BadInputIsRejected) {
  const Image a = Constant(8, 8, 0), b = Constant(9, 8, 0);
  EXPECT_THROW(MaskedPsnr(a, b), std::invalid_argument);
  EXPECT_THROW(MaskedPsnr(a, a, Image(8, 8, 1)), std::invalid_argument);  // empty mask region
  EXPECT_THROW(MaskedSsim(a, a, Image(4, 4, 1)), std::invalid_argument);
  EXPECT_THROW(UnionMask(Image(4, 4, 1), Image(5, 4, 1)), std::invalid_argument);
}

TEST(ImageMetricsTest, UnionAndDifference) {
  Image m1(4, 1, 1), m2(4, 1, 1);
  m1.data = {255, 0, 0, 0};
  m2.data = {0, 0, 7, 0};
  EXPECT_EQ(UnionMask(m1, m2).data, (std::vector<std::uint8_t>{255, 0, 255, 0}));
  const Image d = AbsoluteDifference(Constant(2, 2, 0), Constant(2, 2, 51));
  ASSERT_EQ(d.type, PixelType::kFloat32);
  EXPECT_NEAR(d.at<float>(1, 1), 0.2f, 1e-6);
}

// SSIM inside a mask uses the 11x11 windows around the masked pixels as a whole-image SSIM does:
// pixels up to 5 px outside the mask's box take part, farther ones do not, also where the box
// touches the image border (reflected there).
TEST(MaskedSsimTest, TheWindowsSeeFiveSurroundingPixelsAndNoMore) {
  const Image a = Noise(64, 48, 5), b = Noise(64, 48, 6);
  for (const auto& [x0, y0] : {std::pair{20, 15}, std::pair{0, 0}}) {  // inside, and at the corner
    Image mask(64, 48, 1);
    for (int y = y0; y < y0 + 12; ++y)
      for (int x = x0; x < x0 + 16; ++x) mask.at<std::uint8_t>(x, y) = 255;
    const double ssim = MaskedSsim(a, b, mask);
    auto with_pixel_changed = [&](int x, int y) {
      Image changed = b;
      for (int c = 0; c < 3; ++c) changed.at<std::uint8_t>(x, y, c) ^= 0x80;
      return MaskedSsim(a, changed, mask);
    };
    EXPECT_NE(with_pixel_changed(x0 + 16 + 4, y0 + 5), ssim) << "4 px right of the box";
    EXPECT_NE(with_pixel_changed(x0 + 8, y0 + 12 + 4), ssim) << "4 px below the box";
    EXPECT_EQ(with_pixel_changed(x0 + 16 + 6, y0 + 5), ssim) << "6 px right of the box";
    EXPECT_EQ(with_pixel_changed(x0 + 8, y0 + 12 + 6), ssim) << "6 px below the box";
    // A mask's SSIM is the mean of one SSIM map over its pixels, each pixel's value found by
    // masking that pixel alone (its box is then 1x1, and everything around it is context).
    double sum = 0.0;
    int n = 0;
    for (int y = y0; y < y0 + 12; y += 5)
      for (int x = x0; x < x0 + 16; x += 5) {
        Image one(64, 48, 1);
        one.at<std::uint8_t>(x, y) = 255;
        sum += MaskedSsim(a, b, one);
        ++n;
      }
    Image sparse(64, 48, 1);
    for (int y = y0; y < y0 + 12; y += 5)
      for (int x = x0; x < x0 + 16; x += 5) sparse.at<std::uint8_t>(x, y) = 255;
    EXPECT_NEAR(MaskedSsim(a, b, sparse), sum / n, 1e-12);
  }
}

// The metrics read 16-bit and float images on the same [0, 1] scale as 8-bit ones, a 4-channel
// image by its first three channels, and a mask by its first channel.
TEST(ImageMetricsTest, PixelTypesChannelsAndMaskChannels) {
  const Image a8 = Noise(16, 12, 7), b8 = Noise(16, 12, 8);
  Image a16(16, 12, 3, PixelType::kUInt16), b4(16, 12, 4);
  for (std::size_t i = 0; i < a8.data.size(); ++i) a16.ptr<std::uint16_t>()[i] = static_cast<std::uint16_t>(a8.data[i] * 257);
  for (int p = 0; p < 16 * 12; ++p) {
    for (int c = 0; c < 3; ++c) b4.data[4 * p + c] = b8.data[3 * p + c];
    b4.data[4 * p + 3] = static_cast<std::uint8_t>(p);  // alpha: not compared
  }
  Image mask(16, 12, 2);
  for (int p = 0; p < 16 * 12; ++p) {
    mask.data[2 * p] = p % 3 == 0 ? 255 : 0;
    mask.data[2 * p + 1] = 255;  // second channel: ignored
  }
  Image mask1(16, 12, 1);
  for (int p = 0; p < 16 * 12; ++p) mask1.data[p] = p % 3 == 0 ? 255 : 0;
  EXPECT_NEAR(MaskedPsnr(a16, b4, mask), MaskedPsnr(a8, b8, mask1), 1e-9);
  EXPECT_NEAR(MaskedSsim(a16, b4, mask), MaskedSsim(a8, b8, mask1), 1e-9);
  // By hand: the masked pixels' squared differences over 3 channels.
  double sum = 0.0;
  int n = 0;
  for (int p = 0; p < 16 * 12; p += 3)
    for (int c = 0; c < 3; ++c, ++n) {
      const double d = (a8.data[3 * p + c] - b8.data[3 * p + c]) / 255.0;
      sum += d * d;
    }
  EXPECT_NEAR(MaskedPsnr(a8, b8, mask1), -10.0 * std::log10(sum / n), 1e-9);
  const Image d = AbsoluteDifference(a16, b4);
  EXPECT_NEAR(d.at<float>(5, 7),
              (std::abs(a8.at<std::uint8_t>(5, 7, 0) - b8.at<std::uint8_t>(5, 7, 0)) +
               std::abs(a8.at<std::uint8_t>(5, 7, 1) - b8.at<std::uint8_t>(5, 7, 1)) +
               std::abs(a8.at<std::uint8_t>(5, 7, 2) - b8.at<std::uint8_t>(5, 7, 2))) / (3 * 255.0),
              1e-6);
}

}  // namespace
}  // namespace confluent
