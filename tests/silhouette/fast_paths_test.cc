// The fast paths of silhouette extraction against plain reference implementations: the
// vectorised classification loop (every instruction set this CPU has) against the per-pixel
// definition, bit for bit; the run-based, cropped mask clean-up against whole-frame OpenCV
// morphology and connected components, on random masks.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "core/cv_interop.h"
#include "silhouette/classify_kernel.h"
#include "silhouette/mask_cleanup.h"

namespace confluent {
namespace {

TEST(ClassifyKernel, EveryInstructionSetMatchesTheReferenceBitForBit) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> byte(0, 255), code(1, 255), offset(-12, 12);
  // An odd count exercises the vector loops' tails.
  const std::size_t count = 20011;
  std::vector<std::uint8_t> rgb(3 * count), planes(6 * count), expected(count);
  std::vector<ClassifyParams> settings(3);
  settings[1].chroma_threshold_sq = 9.0f;
  settings[1].chroma_relative_sq = 4e-4f;
  settings[2].chroma_threshold_sq = 51.3f;
  settings[2].chroma_relative_sq = 0.0f;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint8_t* plane = &planes[i];
    for (int c = 0; c < 3; ++c) plane[c * count] = static_cast<std::uint8_t>(code(rng));
    plane[3 * count] = static_cast<std::uint8_t>(i % 7 == 0 ? code(rng) : 1 + byte(rng) % 40);
    plane[4 * count] = static_cast<std::uint8_t>(byte(rng));
    plane[5 * count] = static_cast<std::uint8_t>(byte(rng));
    // Mostly near the mean (decisions close to the thresholds), sometimes anything, and scaled
    // copies of the mean (pure brightness changes, where rounding decides the chroma test).
    for (int c = 0; c < 3; ++c) {
      const int mean = plane[c * count];
      int value = mean + offset(rng);
      if (i % 5 == 0) value = byte(rng);
      if (i % 11 == 0) value = static_cast<int>(std::lround(mean * (0.3 + 0.1 * (i % 13))));
      rgb[3 * i + c] = static_cast<std::uint8_t>(std::clamp(value, 0, 255));
    }
  }
  const ClassifyPlanes model = PlanesOf(planes.data(), count);
  int isas_run = 0;
  for (const ClassifyParams& params : settings) {
    std::size_t foreground = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const std::uint8_t mean[3] = {model.mean_r[i], model.mean_g[i], model.mean_b[i]};
      expected[i] = ClassifyPixelReference(&rgb[3 * i], mean, model.spread[i], model.low[i], model.high[i], params)
                        ? 255 : 0;
      foreground += expected[i] != 0;
    }
    // Both classes occur often: the comparison is not vacuous.
    EXPECT_GT(foreground, count / 10);
    EXPECT_LT(foreground, count * 9 / 10);
    for (ClassifyIsa isa : {ClassifyIsa::kBaseline, ClassifyIsa::kAvx2, ClassifyIsa::kAvx512}) {
      if (!ClassifyIsaSupported(isa)) continue;
      ++isas_run;
      SCOPED_TRACE("instruction set " + std::to_string(static_cast<int>(isa)));
      // Offsets into the buffers: unaligned starts as well.
      for (std::size_t start : {std::size_t{0}, std::size_t{3}}) {
        std::vector<std::uint8_t> mask(count, 7);
        ClassifyPlanes shifted = model;
        for (const std::uint8_t** plane : {&shifted.mean_r, &shifted.mean_g, &shifted.mean_b, &shifted.spread,
                                           &shifted.low, &shifted.high})
          *plane += start;
        ClassifyPixels(&rgb[3 * start], shifted, count - start, params, &mask[start], isa);
        int differing = 0;
        for (std::size_t i = start; i < count; ++i) differing += mask[i] != expected[i];
        EXPECT_EQ(differing, 0);
      }
    }
  }
  EXPECT_GE(isas_run, 3);  // at least the baseline, for each setting
  // The dispatching entry point uses one of them.
  std::vector<std::uint8_t> mask(count);
  ClassifyPixels(rgb.data(), model, count, settings[2], mask.data());
  EXPECT_TRUE(std::equal(mask.begin(), mask.end(), expected.begin()));
}

// ---- The mask clean-up as it was first written: whole frames, OpenCV throughout. ----

cv::Mat Disk(int radius) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
}

// Gap between two boxes (0 when they overlap), pixels.
double BoxGap(const cv::Rect& a, const cv::Rect& b) {
  const int dx = std::max({0, a.x - (b.x + b.width), b.x - (a.x + a.width)});
  const int dy = std::max({0, a.y - (b.y + b.height), b.y - (a.y + a.height)});
  return std::hypot(dx, dy);
}

Image ReferenceCleanMask(const Image& raw, const MaskCleanupOptions& options, MaskCleanupStats* stats) {
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


// A random raw mask: an actor-like body (ellipse with limbs), a detached hand, holes of several
// sizes, speckle everywhere and a few blobs (some touching the border).
Image RandomRawMask(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  cv::Mat mask = cv::Mat::zeros(height, width, CV_8U);
  const double s = std::min(width, height);
  const cv::Point centre(static_cast<int>(width * (0.3 + 0.4 * unit(rng))), static_cast<int>(height * (0.4 + 0.2 * unit(rng))));
  cv::ellipse(mask, centre, cv::Size(static_cast<int>(0.12 * s), static_cast<int>(0.35 * s)), 0, 0, 360, 255, -1);
  for (int limb = 0; limb < 3; ++limb) {
    const double angle = 2 * M_PI * unit(rng);
    const cv::Point end(centre.x + static_cast<int>(0.3 * s * std::cos(angle)),
                        centre.y + static_cast<int>(0.3 * s * std::sin(angle)));
    cv::line(mask, centre, end, 255, std::max(2, static_cast<int>(0.03 * s)));
  }
  // A hand slightly off the body, and a bigger blob far away.
  cv::circle(mask, centre + cv::Point(static_cast<int>(0.2 * s), static_cast<int>(0.05 * s)),
             std::max(2, static_cast<int>(0.02 * s)), 255, -1);
  cv::circle(mask, cv::Point(width - 3, height - 3), static_cast<int>(0.05 * s), 255, -1);
  // Holes: a tiny one, a mid-sized one, and a large gap.
  cv::circle(mask, centre, std::max(1, static_cast<int>(0.01 * s)), 0, -1);
  cv::circle(mask, centre + cv::Point(0, static_cast<int>(0.15 * s)), std::max(2, static_cast<int>(0.025 * s)), 0, -1);
  cv::rectangle(mask, centre + cv::Point(-static_cast<int>(0.03 * s), -static_cast<int>(0.25 * s)),
                centre + cv::Point(static_cast<int>(0.03 * s), -static_cast<int>(0.1 * s)), 0, -1);
  // Speckle: single pixels and small clusters, foreground and background.
  const int speckles = static_cast<int>(width * height * 0.002);
  for (int k = 0; k < speckles; ++k) {
    const int x = static_cast<int>(unit(rng) * width), y = static_cast<int>(unit(rng) * height);
    const int size = unit(rng) < 0.8 ? 1 : 1 + static_cast<int>(unit(rng) * 4);
    cv::rectangle(mask, cv::Rect(x, y, size, size), k % 3 == 0 ? 0 : 255, -1);
  }
  return ImageFromCvMat(mask);
}

TEST(MaskCleanup, MatchesWholeFrameReferenceOnRandomMasks) {
  struct Case {
    int width, height, scale;
  };
  const Case cases[] = {{320, 240, 0}, {200, 150, 1}, {640, 480, 2}, {1024, 768, 0}, {800, 600, 4}};
  std::vector<MaskCleanupOptions> settings(4);
  settings[1].open_radius_px = 1;
  settings[1].close_radius_px = 2;
  settings[2].connect_radius_px = 0;
  settings[2].max_hole_fraction = 0.05;
  settings[3].connect_radius_px = 6;
  settings[3].max_hole_fraction = 0;
  settings[3].min_part_fraction = 0.0;
  settings[3].max_part_distance_fraction = 2.0;
  int holes_filled = 0, parts_dropped = 0, kept_more_than_one = 0;
  for (const Case& c : cases)
    for (unsigned seed = 1; seed <= 3; ++seed) {
      const Image raw = RandomRawMask(c.width, c.height, seed * 31 + c.width);
      for (std::size_t k = 0; k < settings.size(); ++k) {
        SCOPED_TRACE(std::to_string(c.width) + "x" + std::to_string(c.height) + " scale " + std::to_string(c.scale) +
                     " seed " + std::to_string(seed) + " settings " + std::to_string(k));
        MaskCleanupOptions options = settings[k];
        options.work_scale = c.scale;
        MaskCleanupStats stats, expected_stats;
        const Image mask = CleanMask(raw, options, &stats);
        const Image expected = ReferenceCleanMask(raw, options, &expected_stats);
        ASSERT_EQ(mask.width, expected.width);
        ASSERT_EQ(mask.height, expected.height);
        std::size_t differing = 0;
        for (std::size_t i = 0; i < mask.data.size(); ++i) differing += mask.data[i] != expected.data[i];
        EXPECT_EQ(differing, 0u);
        EXPECT_EQ(stats.parts_kept, expected_stats.parts_kept);
        EXPECT_EQ(stats.parts_dropped, expected_stats.parts_dropped);
        EXPECT_EQ(stats.holes_filled, expected_stats.holes_filled);
        holes_filled += stats.holes_filled;
        parts_dropped += stats.parts_dropped;
        kept_more_than_one += stats.parts_kept > 1;
      }
    }
  // The cases exercise every decision.
  EXPECT_GT(holes_filled, 0);
  EXPECT_GT(parts_dropped, 0);
  EXPECT_GT(kept_more_than_one, 0);
}

TEST(MaskCleanup, EmptyAndFullMasksMatchTheReference) {
  for (int scale : {1, 2, 4}) {
    SCOPED_TRACE("scale " + std::to_string(scale));
    MaskCleanupOptions options;
    options.work_scale = scale;
    MaskCleanupStats stats, expected_stats;
    const Image empty(64, 48, 1);
    const Image cleaned = CleanMask(empty, options, &stats);
    EXPECT_TRUE(std::all_of(cleaned.data.begin(), cleaned.data.end(), [](std::uint8_t v) { return v == 0; }));
    EXPECT_EQ(stats.parts_kept, 0);
    Image full(64, 48, 1);
    std::fill(full.data.begin(), full.data.end(), 255);
    const Image kept = CleanMask(full, options, &stats);
    const Image expected = ReferenceCleanMask(full, options, &expected_stats);
    EXPECT_TRUE(kept.data == expected.data);
    EXPECT_EQ(stats.parts_kept, 1);
    EXPECT_EQ(expected_stats.parts_kept, 1);
    EXPECT_GT(std::count(kept.data.begin(), kept.data.end(), 255), 64 * 48 / 4);
  }
}

}  // namespace
}  // namespace confluent
