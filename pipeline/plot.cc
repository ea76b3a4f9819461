#include "pipeline/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "core/cv_interop.h"

namespace confluent {
namespace {

std::string Number(double value) {
  char text[32];
  const bool whole = std::abs(value - std::round(value)) < 1e-9 * std::max(1.0, std::abs(value));
  std::snprintf(text, sizeof text, whole || std::abs(value) >= 100 ? "%.0f" : std::abs(value) >= 10 ? "%.1f" : "%.3g", value);
  return text;
}

// Round tick values (multiples of 1, 2 or 5 times a power of ten) in [lo, hi], at most about
// `max_count` of them, so that an axis of frames is labelled 0, 20, 40 ... rather than 19.2, 38.4.
std::vector<double> NiceTicks(double lo, double hi, int max_count) {
  const double raw = (hi - lo) / std::max(1, max_count);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10 * power;
  for (double factor : {1.0, 2.0, 5.0})
    if (factor * power >= raw) {
      step = factor * power;
      break;
    }
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step)
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  return ticks;
}

void Text(cv::Mat& canvas, const std::string& text, cv::Point origin, double scale = 0.45,
          cv::Scalar colour = cv::Scalar(30, 30, 30)) {
  cv::putText(canvas, text, origin, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

}  // namespace

Image DrawLineChart(const std::vector<PlotSeries>& series, const std::string& title, const std::string& x_label,
                    const std::string& y_label, int width, int height, double y_min, double y_max) {
  cv::Mat canvas(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = 70, right = 20, top = 40, bottom = 50;
  const cv::Rect area(left, top, width - left - right, height - top - bottom);
  double x_lo = 1e300, x_hi = -1e300, y_lo = 1e300, y_hi = -1e300;
  for (const PlotSeries& s : series) {
    if (s.x.size() != s.y.size()) throw std::invalid_argument("DrawLineChart: x and y differ in length");
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.y[i])) continue;
      x_lo = std::min(x_lo, s.x[i]);
      x_hi = std::max(x_hi, s.x[i]);
      y_lo = std::min(y_lo, s.y[i]);
      y_hi = std::max(y_hi, s.y[i]);
    }
  }
  if (x_lo > x_hi) x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;
  if (x_hi - x_lo < 1e-12) x_hi = x_lo + 1;
  if (y_min < y_max) {
    y_lo = y_min;
    y_hi = y_max;
  } else {
    const double pad = std::max(1e-6, 0.05 * (y_hi - y_lo));
    y_lo -= pad;
    y_hi += pad;
  }
  auto to_pixel = [&](double x, double y) {
    return cv::Point(static_cast<int>(std::lround(area.x + (x - x_lo) / (x_hi - x_lo) * area.width)),
                     static_cast<int>(std::lround(area.y + area.height - (y - y_lo) / (y_hi - y_lo) * area.height)));
  };
  for (double y : NiceTicks(y_lo, y_hi, 5)) {  // grid and ticks
    cv::line(canvas, to_pixel(x_lo, y), to_pixel(x_hi, y), cv::Scalar(225, 225, 225));
    Text(canvas, Number(y), cv::Point(8, to_pixel(x_lo, y).y + 4), 0.4);
  }
  for (double x : NiceTicks(x_lo, x_hi, 6))
    Text(canvas, Number(x), cv::Point(to_pixel(x, y_lo).x - 10, area.y + area.height + 18), 0.4);
  cv::rectangle(canvas, area, cv::Scalar(90, 90, 90));
  Text(canvas, title, cv::Point(left, 24), 0.6);
  Text(canvas, x_label, cv::Point(area.x + area.width / 2 - 30, height - 10));
  Text(canvas, y_label, cv::Point(8, top - 8), 0.4);
  int legend_y = top + 18;
  for (const PlotSeries& s : series) {
    const cv::Scalar colour(s.r, s.g, s.b);  // the canvas is RGB
    std::vector<cv::Point> points;
    for (std::size_t i = 0; i < s.x.size(); ++i)
      if (std::isfinite(s.y[i])) points.push_back(to_pixel(s.x[i], std::clamp(s.y[i], y_lo, y_hi)));
    if (points.size() == 1) cv::circle(canvas, points[0], 3, colour, cv::FILLED, cv::LINE_AA);
    if (points.size() > 1) cv::polylines(canvas, points, false, colour, 2, cv::LINE_AA);
    cv::line(canvas, cv::Point(area.x + area.width - 170, legend_y - 4), cv::Point(area.x + area.width - 145, legend_y - 4),
             colour, 2, cv::LINE_AA);
    Text(canvas, s.label, cv::Point(area.x + area.width - 140, legend_y));
    legend_y += 18;
  }
  return ImageFromCvMat(canvas);
}

Image DrawHeatMap(const Image& values, double max_value, const std::string& title) {
  if (values.channels != 1 || values.type != PixelType::kFloat32)
    throw std::invalid_argument("DrawHeatMap: expected a 1-channel float image");
  cv::Mat scaled;
  AsCvMat(values).convertTo(scaled, CV_8U, 255.0 / std::max(1e-9, max_value));
  cv::Mat bgr;
  cv::applyColorMap(scaled, bgr, cv::COLORMAP_TURBO);
  const int bar_height = 40, title_height = 30;
  cv::Mat canvas(bgr.rows + bar_height + title_height, bgr.cols, CV_8UC3, cv::Scalar(255, 255, 255));
  bgr.copyTo(canvas(cv::Rect(0, title_height, bgr.cols, bgr.rows)));
  cv::Mat ramp(1, 256, CV_8U);
  for (int i = 0; i < 256; ++i) ramp.at<unsigned char>(0, i) = static_cast<unsigned char>(i);
  cv::Mat ramp_colour, bar;
  cv::applyColorMap(ramp, ramp_colour, cv::COLORMAP_TURBO);
  const int bar_width = std::min(bgr.cols - 20, 300);
  cv::resize(ramp_colour, bar, cv::Size(bar_width, 12), 0, 0, cv::INTER_LINEAR);
  bar.copyTo(canvas(cv::Rect(10, title_height + bgr.rows + 6, bar_width, 12)));
  Text(canvas, "0", cv::Point(10, canvas.rows - 6), 0.4);
  Text(canvas, Number(max_value), cv::Point(bar_width - 10, canvas.rows - 6), 0.4);
  Text(canvas, title, cv::Point(10, 20), 0.55);
  cv::Mat rgb;
  cv::cvtColor(canvas, rgb, cv::COLOR_BGR2RGB);  // the colour map is BGR; the text is grey either way
  return ImageFromCvMat(rgb);
}

std::array<int, 4> MaskBox(const Image& mask, double margin) {
  int x0 = mask.width, y0 = mask.height, x1 = -1, y1 = -1;
  for (int y = 0; y < mask.height; ++y)
    for (int x = 0; x < mask.width; ++x)
      if (mask.at<std::uint8_t>(x, y)) x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
  if (x1 < 0) return {0, 0, mask.width, mask.height};
  const int grow_x = static_cast<int>(margin * (x1 - x0 + 1)), grow_y = static_cast<int>(margin * (y1 - y0 + 1));
  x0 = std::max(0, x0 - grow_x), y0 = std::max(0, y0 - grow_y);
  x1 = std::min(mask.width - 1, x1 + grow_x), y1 = std::min(mask.height - 1, y1 + grow_y);
  return {x0, y0, x1 - x0 + 1, y1 - y0 + 1};
}

Image CropImage(const Image& image, const std::array<int, 4>& box) {
  const auto [x, y, width, height] = box;
  if (x < 0 || y < 0 || width <= 0 || height <= 0 || x + width > image.width || y + height > image.height)
    throw std::invalid_argument("CropImage: the box is outside the image");
  Image out(width, height, image.channels, image.type);
  const std::size_t pixel = image.row_bytes() / image.width;
  for (int row = 0; row < height; ++row)
    std::memcpy(out.data.data() + row * out.row_bytes(), image.data.data() + (y + row) * image.row_bytes() + x * pixel,
                out.row_bytes());
  return out;
}

Image SideBySide(const std::vector<Image>& images, const std::vector<std::string>& captions) {
  if (images.empty()) throw std::invalid_argument("SideBySide: no images");
  const int caption_height = 26;
  int width = 0;
  const int height = images[0].height;
  for (const Image& image : images) {
    if (image.height != height || image.channels != 3 || image.type != PixelType::kUInt8)
      throw std::invalid_argument("SideBySide: images must be RGB8 of the same height");
    width += image.width;
  }
  cv::Mat canvas(height + caption_height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  int x = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    AsCvMat(images[i]).copyTo(canvas(cv::Rect(x, caption_height, images[i].width, height)));
    if (i < captions.size()) Text(canvas, captions[i], cv::Point(x + 8, 18), 0.55);
    x += images[i].width;
  }
  return ImageFromCvMat(canvas);
}

}  // namespace confluent
