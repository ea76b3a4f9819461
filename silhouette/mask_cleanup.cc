#include "silhouette/mask_cleanup.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "core/cv_interop.h"
#include "core/error.h"

namespace confluent {

void MaskCleanupOptions::Check() const {
  auto require = [](bool ok, const char* message) {
    if (!ok) throw UsageError(std::string("mask clean-up: ") + message);
  };
  require(work_scale == 0 || work_scale == 1 || work_scale == 2 || work_scale == 4,
          "work_scale must be 0 (automatic), 1, 2 or 4");
  require(open_radius_px >= 0 && open_radius_px <= 20, "open_radius_px must be within [0, 20]");
  require(close_radius_px >= 0 && close_radius_px <= 20, "close_radius_px must be within [0, 20]");
  require(connect_radius_px >= 0 && connect_radius_px <= 20, "connect_radius_px must be within [0, 20]");
  require(min_part_fraction >= 0 && min_part_fraction <= 1, "min_part_fraction must be within [0, 1]");
  require(max_part_distance_fraction >= 0, "max_part_distance_fraction must be non-negative");
  require(max_hole_fraction >= 0 && max_hole_fraction <= 1, "max_hole_fraction must be within [0, 1]");
}

namespace {

cv::Mat Disk(int radius) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
}

// Gap between two boxes (0 when they overlap), pixels.
double BoxGap(const cv::Rect& a, const cv::Rect& b) {
  const int dx = std::max({0, a.x - (b.x + b.width), b.x - (a.x + a.width)});
  const int dy = std::max({0, a.y - (b.y + b.height), b.y - (a.y + a.height)});
  return std::hypot(dx, dy);
}

}  // namespace

Image CleanMask(const Image& raw, const MaskCleanupOptions& options, MaskCleanupStats* stats) {
  MaskCleanupStats local;
  MaskCleanupStats& out_stats = stats ? *stats : local;
  out_stats = {};
  const cv::Mat full = AsCvMat(raw);
  const int scale = options.work_scale > 0 ? options.work_scale : raw.width <= 640 ? 1 : raw.width <= 2048 ? 2 : 4;
  cv::Mat work;
  if (scale == 1) {
    work = full.clone();
  } else {
    // A work pixel is foreground when at least half of its block is.
    cv::resize(full, work, cv::Size((full.cols + scale - 1) / scale, (full.rows + scale - 1) / scale), 0, 0,
               cv::INTER_AREA);
    cv::threshold(work, work, 127, 255, cv::THRESH_BINARY);
  }
  if (options.open_radius_px > 0) cv::morphologyEx(work, work, cv::MORPH_OPEN, Disk(options.open_radius_px));
  if (options.close_radius_px > 0)
    cv::morphologyEx(work, work, cv::MORPH_CLOSE, Disk(options.close_radius_px), cv::Point(-1, -1), 1,
                     cv::BORDER_CONSTANT, cv::Scalar(0));

  // Keep the largest component and the sizeable parts near it; pieces closer than the
  // connection radius count as one component.
  cv::Mat connected;  // a separate buffer: `work` keeps the shape
  if (options.connect_radius_px > 0) {
    cv::morphologyEx(work, connected, cv::MORPH_CLOSE, Disk(options.connect_radius_px), cv::Point(-1, -1), 1,
                     cv::BORDER_CONSTANT, cv::Scalar(0));
  } else {
    connected = work;
  }
  cv::Mat labels, comp_stats, centroids;
  const int count = cv::connectedComponentsWithStats(connected, labels, comp_stats, centroids, 8, CV_32S);
  Image result(raw.width, raw.height, 1);
  if (count <= 1) return result;  // empty
  int largest = 1;
  for (int k = 2; k < count; ++k)
    if (comp_stats.at<int>(k, cv::CC_STAT_AREA) > comp_stats.at<int>(largest, cv::CC_STAT_AREA)) largest = k;
  auto box = [&](int k) {
    return cv::Rect(comp_stats.at<int>(k, cv::CC_STAT_LEFT), comp_stats.at<int>(k, cv::CC_STAT_TOP),
                    comp_stats.at<int>(k, cv::CC_STAT_WIDTH), comp_stats.at<int>(k, cv::CC_STAT_HEIGHT));
  };
  const cv::Rect main_box = box(largest);
  const double main_area = comp_stats.at<int>(largest, cv::CC_STAT_AREA);
  const double max_gap = options.max_part_distance_fraction * std::hypot(main_box.width, main_box.height);
  std::vector<std::uint8_t> keep(count, 0);
  double kept_area = 0;
  for (int k = 1; k < count; ++k) {
    const double area = comp_stats.at<int>(k, cv::CC_STAT_AREA);
    if (k == largest || (area >= options.min_part_fraction * main_area && BoxGap(box(k), main_box) <= max_gap)) {
      keep[k] = 255;
      ++out_stats.parts_kept;
    } else {
      ++out_stats.parts_dropped;
    }
  }
  cv::Mat kept(work.size(), CV_8U);
  for (int y = 0; y < work.rows; ++y) {
    const int* label_row = labels.ptr<int>(y);
    const std::uint8_t* work_row = work.ptr<std::uint8_t>(y);
    std::uint8_t* row = kept.ptr<std::uint8_t>(y);
    for (int x = 0; x < work.cols; ++x) {
      row[x] = keep[label_row[x]] & work_row[x];
      kept_area += row[x] != 0;
    }
  }

  // Fill the small enclosed holes (4-connected background not reaching the border).
  if (options.max_hole_fraction > 0) {
    cv::Mat background = 255 - kept;
    cv::Mat hole_labels, hole_stats, hole_centroids;
    const int holes = cv::connectedComponentsWithStats(background, hole_labels, hole_stats, hole_centroids, 4, CV_32S);
    std::vector<std::uint8_t> fill(holes, 0);
    bool any = false;
    for (int k = 1; k < holes; ++k) {
      const int left = hole_stats.at<int>(k, cv::CC_STAT_LEFT), top = hole_stats.at<int>(k, cv::CC_STAT_TOP);
      const int right = left + hole_stats.at<int>(k, cv::CC_STAT_WIDTH), bottom = top + hole_stats.at<int>(k, cv::CC_STAT_HEIGHT);
      const bool touches = left == 0 || top == 0 || right == work.cols || bottom == work.rows;
      if (!touches && hole_stats.at<int>(k, cv::CC_STAT_AREA) <= options.max_hole_fraction * kept_area) {
        fill[k] = 255;
        any = true;
        ++out_stats.holes_filled;
      }
    }
    if (any)
      for (int y = 0; y < work.rows; ++y) {
        const int* label_row = hole_labels.ptr<int>(y);
        std::uint8_t* row = kept.ptr<std::uint8_t>(y);
        for (int x = 0; x < work.cols; ++x) row[x] |= fill[label_row[x]];
      }
  }

  // Interior from the cleaned mask, boundary band from the full-resolution classification.
  cv::Mat core, band;
  const cv::Mat cross = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
  cv::erode(kept, core, cross, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  cv::dilate(kept, band, cross);
  // Upsampling by lookup: full-resolution pixel (x, y) reads work pixel (x / scale, y / scale).
  std::vector<int> column(raw.width);
  for (int x = 0; x < raw.width; ++x) column[x] = x / scale;
  for (int y = 0; y < raw.height; ++y) {
    const std::uint8_t* core_row = core.ptr<std::uint8_t>(y / scale);
    const std::uint8_t* band_row = band.ptr<std::uint8_t>(y / scale);
    const std::uint8_t* raw_row = raw.data.data() + static_cast<std::size_t>(y) * raw.width;
    std::uint8_t* out = result.data.data() + static_cast<std::size_t>(y) * raw.width;
    if (scale == 1) {
      for (int x = 0; x < raw.width; ++x) out[x] = core_row[x] | (raw_row[x] & band_row[x]);
    } else {
      for (int x = 0; x < raw.width; ++x) out[x] = core_row[column[x]] | (raw_row[x] & band_row[column[x]]);
    }
  }
  return result;
}

}  // namespace confluent
