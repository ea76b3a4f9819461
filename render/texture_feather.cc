// Feather maps of projective texturing: a capped, separable distance transform (BandDistance) and
// the depth-and-feather map of one camera (DepthFeatherMap).

#include "render/texture_feather.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace confluent::render_internal {
namespace {

// The row pass of BandDistance in type T (int16 while 2 cap^2 fits, so that the minima vectorise
// with SSE2's pminsw; else int32).
template <typename T>
void BandDistanceRows(const std::uint8_t* column, int w, int h, int cap, std::int32_t* squared_distance,
                      std::vector<T>* row_buffer, std::vector<T>* best_buffer) {
  const int pad = cap;
  const T cap2 = static_cast<T>(cap * cap);
  row_buffer->assign(static_cast<std::size_t>(w) + 2 * pad, cap2);
  best_buffer->resize(static_cast<std::size_t>(w));
  T* center = row_buffer->data() + pad;
  T* best = best_buffer->data();
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* g = column + static_cast<std::size_t>(y) * w;
    for (int x = 0; x < w; ++x) center[x] = static_cast<T>(g[x] * g[x]);
    for (int x = 0; x < w; ++x) best[x] = center[x];
    for (int dx = 1; dx < cap; ++dx) {
      const T d2 = static_cast<T>(dx * dx);
      const T* left = center - dx;
      const T* right = center + dx;
      for (int x = 0; x < w; ++x) best[x] = std::min(best[x], static_cast<T>(std::min(left[x], right[x]) + d2));
    }
    std::int32_t* out = squared_distance + static_cast<std::size_t>(y) * w;
    for (int x = 0; x < w; ++x) out[x] = std::min(best[x], cap2);
  }
}

// Squared Euclidean distance from every pixel of a w x h image to the nearest pixel where
// `not_edge` is 0, exact where the distance is below `cap` (pixels, 1..250), cap^2 elsewhere: a
// separable transform (column distances capped at `cap`, then the minimum of dx^2 + column^2 over
// |dx| < cap), linear in the pixels and vectorisable, instead of a full distance transform.
void BandDistance(const std::uint8_t* not_edge, int w, int h, int cap, std::int32_t* squared_distance,
                  FeatherScratch* scratch) {
  std::vector<std::uint8_t>& column = scratch->column;
  column.resize(static_cast<std::size_t>(w) * h);
  const std::uint8_t c8 = static_cast<std::uint8_t>(cap);
  // Down, then up: distance along the column, capped (values <= cap <= 250: no overflow).
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* e = not_edge + static_cast<std::size_t>(y) * w;
    std::uint8_t* g = column.data() + static_cast<std::size_t>(y) * w;
    if (y == 0) {
      for (int x = 0; x < w; ++x) g[x] = e[x] == 0 ? 0 : c8;
      continue;
    }
    const std::uint8_t* above = g - w;
    for (int x = 0; x < w; ++x) {
      const std::uint8_t from_above = std::min(static_cast<std::uint8_t>(above[x] + 1), c8);
      g[x] = e[x] == 0 ? 0 : from_above;
    }
  }
  for (int y = h - 2; y >= 0; --y) {
    std::uint8_t* g = column.data() + static_cast<std::size_t>(y) * w;
    const std::uint8_t* below = g + w;
    for (int x = 0; x < w; ++x) g[x] = std::min(g[x], static_cast<std::uint8_t>(below[x] + 1));
  }
  // Along the rows: d^2 = min over dx of dx^2 + column(x + dx)^2; outside the image: cap.
  if (cap <= 127) {
    BandDistanceRows(column.data(), w, h, cap, squared_distance, &scratch->row16, &scratch->best16);
  } else {
    BandDistanceRows(column.data(), w, h, cap, squared_distance, &scratch->row32, &scratch->best32);
  }
}

}  // namespace

// Depth and feather map of one camera, interleaved into `out` (2 floats per pixel, w x h):
// camera z (0 = not covered) and smoothstep(0, feather_px, distance to the nearest outline pixel
// of the mesh, depth discontinuity or mask outline), 0 outside the mesh or the mask; feather_px in
// map pixels. `z` may be nonzero only inside `z_box`. `out` is zero outside *written (the region
// the previous call wrote), and only the region around the covered pixels is rewritten; *written
// becomes that region. Returns the number of covered pixels. Thread-safe (reads only its
// arguments, writes only `out`, *written and *scratch).
int DepthFeatherMap(const float* z, int w, int h, const PixelBox& z_box, const Image& mask,
                    const ProjectiveTextureOptions& options, double feather_px, float* out, PixelBox* written,
                    FeatherScratch* scratch) {
  FillBox(out, w, *written, 0.0f, 2);
  *written = PixelBox();
  // Region of interest: covered pixels plus the feather margin.
  int min_x = w, min_y = h, max_x = -1, max_y = -1, count = 0;
  for (int y = std::max(z_box.y0, 0); y < std::min(z_box.y1, h); ++y) {
    const float* row = z + static_cast<std::size_t>(y) * w;
    const int bx0 = std::max(z_box.x0, 0), bx1 = std::min(z_box.x1, w);
    int row_count = 0;
    for (int x = bx0; x < bx1; ++x) row_count += row[x] > 0.0f ? 1 : 0;
    if (row_count > 0) {
      int row_min = bx0, row_max = bx1 - 1;
      while (!(row[row_min] > 0.0f)) ++row_min;
      while (!(row[row_max] > 0.0f)) --row_max;
      count += row_count;
      min_x = std::min(min_x, row_min);
      max_x = std::max(max_x, row_max);
      min_y = std::min(min_y, y);
      max_y = y;
    }
  }
  if (count == 0) return 0;
  const bool use_mask = !mask.empty();
  const std::uint8_t* mask_data = use_mask ? mask.data.data() : nullptr;
  auto covered_in_mask = [&](std::size_t p) { return z[p] > 0.0f && (!use_mask || mask_data[p] != 0); };
  const int margin = static_cast<int>(std::ceil(feather_px)) + 2;
  const int x0 = std::max(0, min_x - margin), y0 = std::max(0, min_y - margin);
  const int x1 = std::min(w - 1, max_x + margin), y1 = std::min(h - 1, max_y + margin);
  const int rw = x1 - x0 + 1, rh = y1 - y0 + 1;
  *written = PixelBox{x0, y0, x1 + 1, y1 + 1};
  for (int y = y0; y <= y1; ++y) {
    const float* row = z + static_cast<std::size_t>(y) * w;
    float* out_row = out + 2 * static_cast<std::size_t>(y) * w;
    for (int x = x0; x <= x1; ++x) out_row[2 * x] = row[x];
  }
  if (feather_px <= 0.0) {
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * w + x;
        out[2 * p + 1] = covered_in_mask(p) ? 1.0f : 0.0f;
      }
    return count;
  }
  // Edge pixels are 0, others 255. A pixel is an edge when a 4-neighbour differs in coverage, in
  // depth by more than depth_edge_m (both covered), or in the mask; a covered pixel on the image
  // border is an edge too (the border is an edge of what the camera sees). Branch-free over a
  // padded copy: uncovered pixels, and the padding, get depth -1e6 (so that any coverage change is
  // a depth jump); the mask's padding repeats its border (mask edges near the region's border
  // are farther than the feather width from any covered pixel).
  const int pw = rw + 2;
  std::vector<float>& padded = scratch->padded;
  padded.assign(static_cast<std::size_t>(pw) * (rh + 2), -1e6f);
  std::vector<std::uint8_t>& padded_mask = scratch->padded_mask;
  const bool mask_edges = use_mask && options.feather_mask_edges;
  if (mask_edges) padded_mask.resize(padded.size());
  for (int y = y0; y <= y1; ++y) {
    const float* row = z + static_cast<std::size_t>(y) * w;
    float* prow = padded.data() + static_cast<std::size_t>(y - y0 + 1) * pw + 1;
    for (int x = x0; x <= x1; ++x) prow[x - x0] = row[x] > 0.0f ? row[x] : -1e6f;
    if (mask_edges) {
      const std::uint8_t* mrow = mask_data + static_cast<std::size_t>(y) * w;
      std::uint8_t* pm = padded_mask.data() + static_cast<std::size_t>(y - y0 + 1) * pw + 1;
      for (int x = x0; x <= x1; ++x) pm[x - x0] = mrow[x] != 0 ? 1 : 0;
      pm[-1] = pm[0];
      pm[rw] = pm[rw - 1];
    }
  }
  if (mask_edges) {
    std::copy_n(padded_mask.data() + pw, pw, padded_mask.data());
    std::copy_n(padded_mask.data() + static_cast<std::size_t>(rh) * pw, pw,
                padded_mask.data() + static_cast<std::size_t>(rh + 1) * pw);
  }
  std::vector<std::uint8_t>& not_edge = scratch->not_edge;
  not_edge.resize(static_cast<std::size_t>(rw) * rh);
  const float jump = static_cast<float>(options.depth_edge_m);
  for (int y = 0; y < rh; ++y) {
    const float* pc = padded.data() + static_cast<std::size_t>(y + 1) * pw + 1;
    const float* pu = pc - pw;
    const float* pd = pc + pw;
    std::uint8_t* edge_row = not_edge.data() + static_cast<std::size_t>(y) * rw;
    for (int x = 0; x < rw; ++x) {
      const float d = pc[x];
      const float m = std::max(std::max(std::abs(pc[x - 1] - d), std::abs(pc[x + 1] - d)),
                               std::max(std::abs(pu[x] - d), std::abs(pd[x] - d)));
      edge_row[x] = m > jump ? 0 : 255;
    }
    if (mask_edges) {
      const std::uint8_t* mc = padded_mask.data() + static_cast<std::size_t>(y + 1) * pw + 1;
      const std::uint8_t* mu = mc - pw;
      const std::uint8_t* md = mc + pw;
      for (int x = 0; x < rw; ++x) {
        const std::uint8_t differs = (mc[x - 1] ^ mc[x]) | (mc[x + 1] ^ mc[x]) | (mu[x] ^ mc[x]) | (md[x] ^ mc[x]);
        edge_row[x] = differs ? 0 : edge_row[x];
      }
    }
  }
  // Euclidean distance to the nearest edge pixel, exact below `cap` (feathering saturates there).
  const int cap = static_cast<int>(std::ceil(feather_px)) + 1;
  std::vector<std::int32_t>& squared_distance = scratch->squared_distance;
  squared_distance.resize(static_cast<std::size_t>(rw) * rh);
  if (cap <= 250) {
    BandDistance(not_edge.data(), rw, rh, cap, squared_distance.data(), scratch);
  } else {  // a feather wider than 249 pixels: a full distance transform
    cv::Mat distance;
    cv::distanceTransform(cv::Mat(rh, rw, CV_8U, not_edge.data()), distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    for (int y = 0; y < rh; ++y)
      for (int x = 0; x < rw; ++x) {
        const double d = std::min<double>(distance.at<float>(y, x), cap);
        squared_distance[static_cast<std::size_t>(y) * rw + x] = static_cast<std::int32_t>(std::lround(d * d));
      }
  }
  const float width = static_cast<float>(feather_px);
  // Feather 1 from distance + 0.5 >= feather_px on: no square root there.
  const float saturated = std::max(0.0f, width - 0.5f);
  const std::int32_t saturated_squared = static_cast<std::int32_t>(std::ceil(saturated * saturated));
  for (int y = y0; y <= y1; ++y) {
    const std::int32_t* distance_row = squared_distance.data() + static_cast<std::size_t>(y - y0) * rw;
    for (int x = x0; x <= x1; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * w + x;
      float feather = 0.0f;
      if (covered_in_mask(p)) {
        const std::int32_t d2 = distance_row[x - x0];
        // +0.5: an edge pixel itself is half a pixel from the outline.
        feather = d2 >= saturated_squared ? 1.0f : Smoothstep(width, std::sqrt(static_cast<float>(d2)) + 0.5f);
      }
      out[2 * p + 1] = feather;
    }
  }
  return count;
}

}  // namespace confluent::render_internal
