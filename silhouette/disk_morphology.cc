#include "silhouette/disk_morphology.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace confluent {
namespace {

// The box around `mask`'s nonzero pixels grown by `margin`, within the image; empty when the
// mask is.
cv::Rect WorkBox(const cv::Mat& mask, int margin) {
  const cv::Rect box = cv::boundingRect(mask);
  if (box.empty()) return box;
  return (box + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) & cv::Rect(0, 0, mask.cols, mask.rows);
}

// `operation` applied to the mask's box grown by `margin` pixels; zero elsewhere. Exact whenever
// the operation leaves every pixel farther than `margin - 1` from the mask's box at zero and reads
// no further than `margin - 1` beyond a set pixel's box (true of the three below).
template <typename Operation>
cv::Mat InBox(const cv::Mat& mask, int margin, Operation operation) {
  cv::Mat result = cv::Mat::zeros(mask.size(), CV_8U);
  const cv::Rect box = WorkBox(mask, margin);
  if (box.empty()) return result;
  cv::Mat worked;
  operation(mask(box), worked);
  worked.copyTo(result(box));
  return result;
}

}  // namespace

cv::Mat Disk(int radius) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
}

int ScaledRadius(double per_1000, int width) {
  if (per_1000 <= 0) return 0;
  return std::max(1, static_cast<int>(std::lround(per_1000 * width / 1000.0)));
}

cv::Mat DilateByDisk(const cv::Mat& mask, int radius) {
  if (radius <= 0) return mask.clone();
  return InBox(mask, radius + 1, [&](const cv::Mat& in, cv::Mat& out) { cv::dilate(in, out, Disk(radius)); });
}

cv::Mat ErodeByDisk(const cv::Mat& mask, int radius) {
  if (radius <= 0) return mask.clone();
  // A set pixel is at least radius + 1 from the box's inner edges, so the box's border (counted
  // as set, as the image's is) never reaches it there.
  return InBox(mask, radius + 1, [&](const cv::Mat& in, cv::Mat& out) { cv::erode(in, out, Disk(radius)); });
}

cv::Mat CloseByDisk(const cv::Mat& mask, int radius) {
  if (radius <= 0) return mask.clone();
  return InBox(mask, radius + 1, [&](const cv::Mat& in, cv::Mat& out) {
    cv::morphologyEx(in, out, cv::MORPH_CLOSE, Disk(radius), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT,
                     cv::Scalar(0));
  });
}

}  // namespace confluent
