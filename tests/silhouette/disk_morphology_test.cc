// The box-limited disk morphology gives exactly what OpenCV gives over the whole image.

#include "silhouette/disk_morphology.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

namespace confluent {
namespace {

// Blobs (ellipses, thin lines, single pixels) placed at random, some over the image's edges,
// with pinholes cut into them.
cv::Mat RandomMask(unsigned seed, int width, int height) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> x(-20, width + 20), y(-20, height + 20), size(1, 40);
  cv::Mat mask = cv::Mat::zeros(height, width, CV_8U);
  for (int k = 0; k < 6; ++k) {
    const cv::Point centre(x(rng), y(rng));
    switch (k % 3) {
      case 0: cv::ellipse(mask, centre, cv::Size(size(rng), size(rng)), 30.0 * k, 0, 360, cv::Scalar(255), -1); break;
      case 1: cv::line(mask, centre, cv::Point(x(rng), y(rng)), cv::Scalar(255), 1 + k % 2); break;
      default: mask.at<std::uint8_t>(std::clamp(centre.y, 0, height - 1), std::clamp(centre.x, 0, width - 1)) = 255;
    }
  }
  for (int k = 0; k < 30; ++k)
    mask.at<std::uint8_t>(std::clamp(y(rng), 0, height - 1), std::clamp(x(rng), 0, width - 1)) = 0;
  return mask;
}

int Differing(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat difference;
  cv::compare(a, b, difference, cv::CMP_NE);
  return cv::countNonZero(difference);
}

TEST(DiskMorphology, MatchesOpenCvOverTheWholeImage) {
  int set_after_closing = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    const cv::Mat mask = RandomMask(seed, 160 + 7 * seed, 120);
    for (int radius : {0, 1, 3, 9, 25}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", radius " + std::to_string(radius));
      cv::Mat dilated, eroded, closed;
      const cv::Mat disk = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
      cv::dilate(mask, dilated, disk);
      cv::erode(mask, eroded, disk);
      cv::morphologyEx(mask, closed, cv::MORPH_CLOSE, disk, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
      EXPECT_EQ(Differing(DilateByDisk(mask, radius), dilated), 0);
      EXPECT_EQ(Differing(ErodeByDisk(mask, radius), eroded), 0);
      EXPECT_EQ(Differing(CloseByDisk(mask, radius), closed), 0);
      set_after_closing += cv::countNonZero(closed);
    }
  }
  EXPECT_GT(set_after_closing, 0);  // the masks were not all empty
}

TEST(DiskMorphology, EmptyMaskStaysEmptyAndTheInputIsKept) {
  const cv::Mat empty = cv::Mat::zeros(50, 60, CV_8U);
  EXPECT_EQ(cv::countNonZero(DilateByDisk(empty, 5)), 0);
  EXPECT_EQ(cv::countNonZero(ErodeByDisk(empty, 5)), 0);
  EXPECT_EQ(cv::countNonZero(CloseByDisk(empty, 5)), 0);
  const cv::Mat mask = RandomMask(3, 60, 50), copy = mask.clone();
  DilateByDisk(mask, 4);
  CloseByDisk(mask, 4);
  EXPECT_EQ(Differing(mask, copy), 0);
}

TEST(DiskMorphology, ScaledRadiusFollowsTheImageWidth) {
  EXPECT_EQ(ScaledRadius(0.0, 1024), 0);
  EXPECT_EQ(ScaledRadius(40.0, 1024), 41);
  EXPECT_EQ(ScaledRadius(40.0, 160), 6);
  EXPECT_EQ(ScaledRadius(1.0, 160), 1);  // at least one pixel when positive
}

}  // namespace
}  // namespace confluent
