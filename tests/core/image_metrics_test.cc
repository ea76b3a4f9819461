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

}  // namespace
}  // namespace confluent
