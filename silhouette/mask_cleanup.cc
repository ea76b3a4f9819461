#include "silhouette/mask_cleanup.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "core/cv_interop.h"
#include "core/error.h"
#include "silhouette/disk_morphology.h"

namespace confluent {

void MaskCleanupOptions::Check() const {
  const std::string owner = "MaskCleanupOptions.";
  RequireOption(work_scale == 0 || work_scale == 1 || work_scale == 2 || work_scale == 4, owner + "work_scale",
                work_scale, "0 (automatic), 1, 2 or 4");
  RequireOption(open_radius_px >= 0 && open_radius_px <= 20, owner + "open_radius_px", open_radius_px, "in [0, 20]");
  RequireOption(close_radius_px >= 0 && close_radius_px <= 20, owner + "close_radius_px", close_radius_px,
                "in [0, 20]");
  RequireOption(connect_radius_px >= 0 && connect_radius_px <= 20, owner + "connect_radius_px", connect_radius_px,
                "in [0, 20]");
  RequireOption(min_part_fraction >= 0 && min_part_fraction <= 1, owner + "min_part_fraction", min_part_fraction,
                "in [0, 1]");
  RequireOption(max_part_distance_fraction >= 0, owner + "max_part_distance_fraction", max_part_distance_fraction,
                ">= 0");
  RequireOption(max_hole_fraction >= 0 && max_hole_fraction <= 1, owner + "max_hole_fraction", max_hole_fraction,
                "in [0, 1]");
}

namespace {

// Gap between two boxes (0 when they overlap), pixels.
double BoxGap(const cv::Rect& a, const cv::Rect& b) {
  const int dx = std::max({0, a.x - (b.x + b.width), b.x - (a.x + a.width)});
  const int dy = std::max({0, a.y - (b.y + b.height), b.y - (a.y + a.height)});
  return std::hypot(dx, dy);
}

cv::Rect Grow(const cv::Rect& box, int margin, const cv::Size& bounds) {
  return cv::Rect(box.x - margin, box.y - margin, box.width + 2 * margin, box.height + 2 * margin) &
         cv::Rect(0, 0, bounds.width, bounds.height);
}

std::uint64_t Load8(const std::uint8_t* p) {
  std::uint64_t word;
  std::memcpy(&word, p, 8);
  return word;
}

// Whether any byte of `word` is zero.
bool HasZeroByte(std::uint64_t word) {
  return ((word - 0x0101010101010101ull) & ~word & 0x8080808080808080ull) != 0;
}

// A horizontal run [x0, x1) of row y; `parent` links runs of one component (union-find; the
// root is the component's first run in raster order).
struct Run {
  int y, x0, x1, parent;
};

int FindRoot(std::vector<Run>& runs, int i) {
  while (runs[i].parent != i) {
    runs[i].parent = runs[runs[i].parent].parent;
    i = runs[i].parent;
  }
  return i;
}

void Unite(std::vector<Run>& runs, int a, int b) {
  a = FindRoot(runs, a);
  b = FindRoot(runs, b);
  if (a < b) runs[b].parent = a;
  if (b < a) runs[a].parent = b;
}

// Appends the runs of foreground (nonzero; or, with !kForeground, zero) pixels of one row.
template <bool kForeground>
void AppendRuns(const std::uint8_t* row, int width, int y, std::vector<Run>* runs) {
  auto matches = [](std::uint8_t v) { return kForeground ? v != 0 : v == 0; };
  // Whole words of 8 pixels none of which (all of which) match.
  auto none_match = [](std::uint64_t w) { return kForeground ? w == 0 : !HasZeroByte(w); };
  auto all_match = [](std::uint64_t w) { return kForeground ? !HasZeroByte(w) : w == 0; };
  int x = 0;
  while (x < width) {
    while (x + 8 <= width && none_match(Load8(row + x))) x += 8;
    while (x < width && !matches(row[x])) ++x;
    if (x == width) break;
    const int start = x;
    while (x + 8 <= width && all_match(Load8(row + x))) x += 8;
    while (x < width && matches(row[x])) ++x;
    runs->push_back({y, start, x, static_cast<int>(runs->size())});
  }
}

// One connected component of runs.
struct Component {
  int area = 0;
  cv::Rect box;
};

// Connected components (8- or 4-connected) of the foreground (or background) pixels of `mask`,
// in raster order of their first pixel. On return every run's parent is its component index.
template <bool kForeground>
std::vector<Component> LabelRuns(const cv::Mat& mask, bool eight_connected, std::vector<Run>* runs) {
  runs->clear();
  const int touch = eight_connected ? 1 : 0;  // diagonal neighbours count
  std::size_t previous_begin = 0, previous_end = 0;
  for (int y = 0; y < mask.rows; ++y) {
    const std::size_t begin = runs->size();
    AppendRuns<kForeground>(mask.ptr<std::uint8_t>(y), mask.cols, y, runs);
    const std::size_t end = runs->size();
    std::size_t p = previous_begin;
    for (std::size_t c = begin; c < end; ++c) {
      const Run run = (*runs)[c];
      while (p < previous_end && (*runs)[p].x1 + touch <= run.x0) ++p;
      for (std::size_t q = p; q < previous_end && (*runs)[q].x0 < run.x1 + touch; ++q)
        Unite(*runs, static_cast<int>(q), static_cast<int>(c));
    }
    previous_begin = begin;
    previous_end = end;
  }
  // Roots precede their runs, so one forward pass resolves every run to its component.
  std::vector<Component> components;
  for (std::size_t i = 0; i < runs->size(); ++i) {
    Run& run = (*runs)[i];
    if (run.parent == static_cast<int>(i)) {
      run.parent = static_cast<int>(components.size());
      components.push_back({0, cv::Rect(run.x0, run.y, run.x1 - run.x0, 1)});
    } else {
      run.parent = (*runs)[run.parent].parent;
    }
    Component& component = components[run.parent];
    component.area += run.x1 - run.x0;
    component.box |= cv::Rect(run.x0, run.y, run.x1 - run.x0, 1);
  }
  return components;
}

// Work mask at 1/scale of the resolution: a work pixel is foreground (255) when at least half
// of its block's pixels (fewer at the right and bottom edges) are.
template <int kScale>
cv::Mat Downsample(const Image& raw) {
  const int w = raw.width, h = raw.height;
  cv::Mat work((h + kScale - 1) / kScale, (w + kScale - 1) / kScale, CV_8U);
  const int full_cols = w / kScale;
  std::vector<std::uint8_t> column_sum(static_cast<std::size_t>(w));
  for (int wy = 0; wy < work.rows; ++wy) {
    const int y0 = wy * kScale, rows = std::min(kScale, h - y0);
    std::fill(column_sum.begin(), column_sum.end(), 0);
    for (int dy = 0; dy < rows; ++dy) {
      const std::uint8_t* __restrict row = raw.data.data() + static_cast<std::size_t>(y0 + dy) * w;
      std::uint8_t* __restrict sums = column_sum.data();
      for (int x = 0; x < w; ++x) sums[x] = static_cast<std::uint8_t>(sums[x] + (row[x] != 0));
    }
    std::uint8_t* __restrict out = work.ptr<std::uint8_t>(wy);
    const std::uint8_t* __restrict sums = column_sum.data();
    const std::uint8_t need = static_cast<std::uint8_t>((rows * kScale + 1) / 2);  // half, rounded up
    for (int wx = 0; wx < full_cols; ++wx) {
      std::uint8_t count = 0;
      for (int k = 0; k < kScale; ++k) count = static_cast<std::uint8_t>(count + sums[wx * kScale + k]);
      out[wx] = count >= need ? 255 : 0;
    }
    if (full_cols < work.cols) {
      const int cols = w - full_cols * kScale;
      int count = 0;
      for (int k = 0; k < cols; ++k) count += column_sum[full_cols * kScale + k];
      out[full_cols] = 2 * count >= rows * cols ? 255 : 0;
    }
  }
  return work;
}

// Bounding box of the nonzero pixels of `mask` (empty when there are none).
cv::Rect ForegroundBox(const cv::Mat& mask) {
  int x0 = mask.cols, x1 = 0, y0 = mask.rows, y1 = 0;
  for (int y = 0; y < mask.rows; ++y) {
    const std::uint8_t* row = mask.ptr<std::uint8_t>(y);
    int first = 0;
    while (first + 8 <= mask.cols && Load8(row + first) == 0) first += 8;
    while (first < mask.cols && row[first] == 0) ++first;
    if (first == mask.cols) continue;
    int last = mask.cols;
    while (last - 8 >= first && Load8(row + last - 8) == 0) last -= 8;
    while (row[last - 1] == 0) --last;
    x0 = std::min(x0, first);
    x1 = std::max(x1, last);
    y0 = std::min(y0, y);
    y1 = y + 1;
  }
  return y1 > y0 ? cv::Rect(x0, y0, x1 - x0, y1 - y0) : cv::Rect();
}

// Repeats each of the first `count` / kScale (rounded up) values of `row` kScale times.
template <int kScale>
void ExpandRow(const std::uint8_t* row, int count, std::uint8_t* out) {
  const int whole = count / kScale;
  for (int i = 0; i < whole; ++i)
    for (int k = 0; k < kScale; ++k) out[i * kScale + k] = row[i];
  for (int x = whole * kScale; x < count; ++x) out[x] = row[whole];
}

}  // namespace

Image CleanMask(const Image& raw, const MaskCleanupOptions& options, MaskCleanupStats* stats) {
  MaskCleanupStats local;
  MaskCleanupStats& out_stats = stats ? *stats : local;
  out_stats = {};
  Image result(raw.width, raw.height, 1);
  const int scale = options.work_scale > 0 ? options.work_scale : raw.width <= 640 ? 1 : raw.width <= 2048 ? 2 : 4;
  cv::Mat work = scale == 1 ? AsCvMat(raw) : scale == 2 ? Downsample<2>(raw) : Downsample<4>(raw);
  if (options.open_radius_px > 0 || options.close_radius_px > 0) {
    if (scale == 1) work = work.clone();  // do not write into `raw`
    if (options.open_radius_px > 0) cv::morphologyEx(work, work, cv::MORPH_OPEN, Disk(options.open_radius_px));
    if (options.close_radius_px > 0)
      cv::morphologyEx(work, work, cv::MORPH_CLOSE, Disk(options.close_radius_px), cv::Point(-1, -1), 1,
                       cv::BORDER_CONSTANT, cv::Scalar(0));
  }
  // Everything below works inside the foreground's bounding box, grown by the connection
  // radius: outside it every intermediate mask is zero, so the result is that of whole frames.
  const cv::Rect foreground = ForegroundBox(work);
  if (foreground.empty()) return result;
  const int radius = options.connect_radius_px;
  const cv::Rect roi = Grow(foreground, std::max(radius, 1), work.size());
  const cv::Mat work_roi = work(roi).clone();

  // Keep the largest component and the sizeable parts near it; pieces closer than the
  // connection radius count as one component. The closing sees zeros beyond the box, as it
  // would in the whole frame.
  cv::Mat connected;  // a separate buffer: `work_roi` keeps the shape
  if (radius > 0) {
    cv::morphologyEx(work_roi, connected, cv::MORPH_CLOSE, Disk(radius), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT,
                     cv::Scalar(0));
  } else {
    connected = work_roi;
  }
  std::vector<Run> runs;
  const std::vector<Component> parts = LabelRuns<true>(connected, true, &runs);
  if (parts.empty()) return result;
  std::size_t largest = 0;  // on a tie, the part that starts first in raster order
  for (std::size_t k = 1; k < parts.size(); ++k)
    if (parts[k].area > parts[largest].area) largest = k;
  const cv::Rect main_box = parts[largest].box;
  const double main_area = parts[largest].area;
  const double max_gap = options.max_part_distance_fraction * std::hypot(main_box.width, main_box.height);
  std::vector<bool> keep(parts.size(), false);
  for (std::size_t k = 0; k < parts.size(); ++k) {
    if (k == largest || (parts[k].area >= options.min_part_fraction * main_area &&
                         BoxGap(parts[k].box, main_box) <= max_gap)) {
      keep[k] = true;
      ++out_stats.parts_kept;
    } else {
      ++out_stats.parts_dropped;
    }
  }
  // The kept parts' pixels of the shape.
  cv::Mat kept = cv::Mat::zeros(roi.size(), CV_8U);
  double kept_area = 0;
  int kx0 = roi.width, kx1 = 0, ky0 = roi.height, ky1 = 0;
  for (const Run& run : runs) {
    if (!keep[run.parent]) continue;
    const std::uint8_t* shape_row = work_roi.ptr<std::uint8_t>(run.y);
    std::uint8_t* row = kept.ptr<std::uint8_t>(run.y);
    int count = 0;
    for (int x = run.x0; x < run.x1; ++x) {
      row[x] = shape_row[x];
      count += shape_row[x] != 0;
    }
    if (count == 0) continue;
    kept_area += count;
    kx0 = std::min(kx0, run.x0);
    kx1 = std::max(kx1, run.x1);
    ky0 = std::min(ky0, run.y);
    ky1 = std::max(ky1, run.y + 1);
  }
  if (kept_area == 0) return result;
  // The kept box grown by one pixel lies inside `roi` (grown by at least one) or at the frame's
  // edge; background outside it reaches the frame's border.
  const cv::Rect kept_box = Grow(cv::Rect(kx0 + roi.x, ky0 + roi.y, kx1 - kx0, ky1 - ky0), 1, work.size());
  cv::Mat kept_roi = kept(kept_box - roi.tl());

  // Fill the small enclosed holes (4-connected background not reaching the border; within the
  // grown kept box, not reaching the box's edge).
  if (options.max_hole_fraction > 0) {
    const std::vector<Component> holes = LabelRuns<false>(kept_roi, false, &runs);
    std::vector<bool> fill(holes.size(), false);
    for (std::size_t k = 0; k < holes.size(); ++k) {
      const cv::Rect& box = holes[k].box;
      const bool touches = box.x == 0 || box.y == 0 || box.x + box.width == kept_roi.cols ||
                           box.y + box.height == kept_roi.rows;
      if (!touches && holes[k].area <= options.max_hole_fraction * kept_area) {
        fill[k] = true;
        ++out_stats.holes_filled;
      }
    }
    for (const Run& run : runs)
      if (fill[run.parent]) std::fill_n(kept_roi.ptr<std::uint8_t>(run.y) + run.x0, run.x1 - run.x0, 255);
  }

  // Interior from the cleaned mask, boundary band from the full-resolution classification.
  // Both are zero outside the grown kept box.
  cv::Mat core, band;
  const cv::Mat cross = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
  cv::erode(kept_roi, core, cross, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  cv::dilate(kept_roi, band, cross);
  const int x_begin = kept_box.x * scale, x_end = std::min(raw.width, (kept_box.x + kept_box.width) * scale);
  const int count = x_end - x_begin;
  std::vector<std::uint8_t> core_up(static_cast<std::size_t>(count)), band_up(static_cast<std::size_t>(count));
  for (int wy = 0; wy < kept_box.height; ++wy) {
    // Full-resolution pixel (x, y) reads work pixel (x / scale, y / scale).
    const std::uint8_t* core_row = core.ptr<std::uint8_t>(wy);
    const std::uint8_t* band_row = band.ptr<std::uint8_t>(wy);
    if (scale == 1) {
      std::copy_n(core_row, count, core_up.data());
      std::copy_n(band_row, count, band_up.data());
    } else if (scale == 2) {
      ExpandRow<2>(core_row, count, core_up.data());
      ExpandRow<2>(band_row, count, band_up.data());
    } else {
      ExpandRow<4>(core_row, count, core_up.data());
      ExpandRow<4>(band_row, count, band_up.data());
    }
    const int y_end = std::min(raw.height, (kept_box.y + wy + 1) * scale);
    for (int y = (kept_box.y + wy) * scale; y < y_end; ++y) {
      const std::size_t offset = static_cast<std::size_t>(y) * raw.width + x_begin;
      const std::uint8_t* __restrict raw_row = raw.data.data() + offset;
      const std::uint8_t* __restrict core_x = core_up.data();
      const std::uint8_t* __restrict band_x = band_up.data();
      std::uint8_t* __restrict out = result.data.data() + offset;
      for (int x = 0; x < count; ++x) out[x] = core_x[x] | (raw_row[x] & band_x[x]);
    }
  }
  return result;
}

}  // namespace confluent
