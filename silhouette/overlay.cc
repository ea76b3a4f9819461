#include "silhouette/overlay.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <opencv2/imgproc.hpp>

#include "calib/capture.h"
#include "core/cv_interop.h"

namespace confluent {

Image DrawMaskOverlay(const Image& image, const Image& mask, int width_px, const std::string& label) {
  const Image rgb = ToRgb8(image);
  if (mask.width != rgb.width || mask.height != rgb.height || mask.channels != 1) std::abort();  // caller's invariant
  cv::Mat picture = AsCvMat(rgb).clone();
  cv::Mat binary = AsCvMat(mask) > 127;
  if (width_px > 0 && width_px != rgb.width) {
    const int height_px = std::max(1, static_cast<int>(std::lround(static_cast<double>(rgb.height) * width_px / rgb.width)));
    cv::resize(picture, picture, cv::Size(width_px, height_px), 0, 0, cv::INTER_AREA);
    cv::Mat scaled;
    cv::resize(binary, scaled, picture.size(), 0, 0, cv::INTER_AREA);
    binary = scaled > 127;
  }
  // Tint the foreground magenta a little, then draw its contour.
  cv::Mat tinted;
  cv::addWeighted(picture, 0.75, cv::Mat(picture.size(), picture.type(), cv::Scalar(255, 0, 255)), 0.25, 0, tinted);
  tinted.copyTo(picture, binary);
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(binary, contours, cv::RETR_LIST, cv::CHAIN_APPROX_SIMPLE);
  const int thickness = std::max(1, picture.cols / 400);
  cv::drawContours(picture, contours, -1, cv::Scalar(255, 255, 0), thickness, cv::LINE_AA);
  if (!label.empty()) {
    const double scale = std::max(0.4, picture.cols / 700.0);
    int baseline = 0;
    const cv::Size text = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
    cv::rectangle(picture, cv::Rect(0, 0, text.width + 8, text.height + baseline + 8), cv::Scalar(0, 0, 0), cv::FILLED);
    cv::putText(picture, label, cv::Point(4, text.height + 4), cv::FONT_HERSHEY_SIMPLEX, scale,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  return ImageFromCvMat(picture);
}

Image TileImages(const std::vector<Image>& tiles, int columns) {
  if (tiles.empty()) return Image();
  const int count = static_cast<int>(tiles.size());
  if (columns <= 0) columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
  columns = std::min(columns, count);
  const int rows = (count + columns - 1) / columns;
  int cell_w = 0, cell_h = 0;
  for (const Image& tile : tiles) {
    cell_w = std::max(cell_w, tile.width);
    cell_h = std::max(cell_h, tile.height);
  }
  constexpr int kGap = 4;
  cv::Mat sheet(rows * (cell_h + kGap) - kGap, columns * (cell_w + kGap) - kGap, CV_8UC3, cv::Scalar(24, 24, 24));
  for (int k = 0; k < count; ++k) {
    const Image rgb = ToRgb8(tiles[k]);
    const int x = (k % columns) * (cell_w + kGap) + (cell_w - rgb.width) / 2;
    const int y = (k / columns) * (cell_h + kGap) + (cell_h - rgb.height) / 2;
    AsCvMat(rgb).copyTo(sheet(cv::Rect(x, y, rgb.width, rgb.height)));
  }
  return ImageFromCvMat(sheet);
}

}  // namespace confluent
