// The per-pixel blending of projective texturing: depth tests against the feather maps, the
// best k cameras by penalty, bilinear samples of their images.

#include "render/texture_blend.h"

#include <algorithm>
#include <cmath>

#include "render/texture_feather.h"

namespace confluent::render_internal {
namespace {

// Camera z of the depth map at the 4 texels around `pixel_in_map` (texel centres at +0.5),
// the farthest of them; texels outside the map count as 0 (not covered).
// map_x, map_y >= 0.
float FarthestDepth(const BlendCamera& camera, float map_x, float map_y) {
  // floor(map - 0.5) by truncation (map + 0.5 > 0).
  const int x0 = static_cast<int>(map_x + 0.5f) - 1, y0 = static_cast<int>(map_y + 0.5f) - 1;
  if (x0 >= 0 && y0 >= 0 && x0 + 1 < camera.map_width && y0 + 1 < camera.map_height) {
    const float* top = camera.depth_feather + 2 * (static_cast<std::size_t>(y0) * camera.map_width + x0);
    const float* bottom = top + 2 * static_cast<std::size_t>(camera.map_width);
    return std::max(std::max(top[0], top[2]), std::max(bottom[0], bottom[2]));
  }
  float depth = 0.0f;
  for (int dy = 0; dy < 2; ++dy) {
    const int y = y0 + dy;
    if (y < 0 || y >= camera.map_height) continue;
    for (int dx = 0; dx < 2; ++dx) {
      const int x = x0 + dx;
      if (x < 0 || x >= camera.map_width) continue;
      depth = std::max(depth, camera.depth_feather[2 * (static_cast<std::size_t>(y) * camera.map_width + x)]);
    }
  }
  return depth;
}

// Bilinear RGB of an RGB8 image at a pixel position (centres at integers, clamped to the edge), in
// [0, 255].
Eigen::Vector3f Bilinear(const BlendCamera& camera, float px, float py) {
  const float fx0 = std::floor(px), fy0 = std::floor(py);
  const float ax = px - fx0, ay = py - fy0;
  const int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
  const int xa = std::clamp(x0, 0, camera.width - 1), xb = std::clamp(x0 + 1, 0, camera.width - 1);
  const int ya = std::clamp(y0, 0, camera.height - 1), yb = std::clamp(y0 + 1, 0, camera.height - 1);
  const std::uint8_t* top = camera.image + 3 * static_cast<std::size_t>(ya) * camera.width;
  const std::uint8_t* bottom = camera.image + 3 * static_cast<std::size_t>(yb) * camera.width;
  Eigen::Vector3f value;
  for (int c = 0; c < 3; ++c) {
    const float t = top[3 * xa + c] + ax * (top[3 * xb + c] - top[3 * xa + c]);
    const float b = bottom[3 * xa + c] + ax * (bottom[3 * xb + c] - bottom[3 * xa + c]);
    value[c] = t + ay * (b - t);
  }
  return value;
}

}  // namespace

// The blended RGB8 colour of surface point X (world) with unit normal n (towards the view) into
// out[0..2] (see the header for the weighting); false, and out untouched, when no camera sees X.
// The cheap tests come first, so that cameras facing away cost little.
bool BlendPixel(const BlendInput& in, const std::vector<BlendCamera>& cameras, const Eigen::Vector3f& X,
                const Eigen::Vector3f& n, std::uint8_t* out) {
  Eigen::Vector3f to_view = in.view_center - X;
  const float view_distance = std::max(to_view.norm(), 1e-6f);
  to_view /= view_distance;
  constexpr int kMaxSlots = 9;
  const int slots = in.best_k + 1;
  float slot_penalty[kMaxSlots], slot_quality[kMaxSlots], slot_x[kMaxSlots], slot_y[kMaxSlots];
  int slot_camera[kMaxSlots];
  for (int s = 0; s < slots; ++s) {
    slot_penalty[s] = 1e30f;
    slot_quality[s] = 0.0f;
    slot_x[s] = slot_y[s] = 0.0f;
    slot_camera[s] = 0;
  }
  // Pass 1: the cameras X faces that it projects into, with their depth-map texels prefetched, so
  // that the cache misses of the cameras overlap instead of following each other.
  struct Candidate {
    int camera;
    float z, px, py, map_x, map_y;
  };
  Candidate candidates[kMaxCameras];
  int num_candidates = 0;
  for (int i = 0; i < static_cast<int>(cameras.size()); ++i) {
    const BlendCamera& camera = cameras[i];
    if (!(n.dot(camera.center - X) > 0.0f)) continue;  // faces away: the cheapest test first
    const Eigen::Vector3f p = camera.rotation * X + camera.translation;
    if (!(p.z() > 1e-6f)) continue;
    float xn = p.x() / p.z(), yn = p.y() / p.z();
    if (camera.distorted) {
      const float r2 = xn * xn + yn * yn;
      const float radial = 1.0f + r2 * (camera.k1 + r2 * (camera.k2 + r2 * camera.k3));
      const float xd = xn * radial + 2.0f * camera.p1 * xn * yn + camera.p2 * (r2 + 2.0f * xn * xn);
      const float yd = yn * radial + camera.p1 * (r2 + 2.0f * yn * yn) + 2.0f * camera.p2 * xn * yn;
      xn = xd;
      yn = yd;
    }
    const float px = camera.fx * xn + camera.skew * yn + camera.cx, py = camera.fy * yn + camera.cy;
    if (!(px >= -0.5f && py >= -0.5f && px <= camera.width - 0.5f && py <= camera.height - 0.5f)) continue;
    Candidate& candidate = candidates[num_candidates++];
    candidate = Candidate{i, p.z(), px, py, (px + 0.5f) * camera.map_scale_x, (py + 0.5f) * camera.map_scale_y};
    const int x0 = std::min(static_cast<int>(candidate.map_x), camera.map_width - 1);
    const int y0 = std::min(static_cast<int>(candidate.map_y + 0.5f), camera.map_height - 1);
    const float* texel = camera.depth_feather + 2 * (static_cast<std::size_t>(y0) * camera.map_width + x0);
    __builtin_prefetch(texel);
    __builtin_prefetch(texel - 2 * static_cast<std::ptrdiff_t>(camera.map_width) * (y0 > 0 ? 1 : 0));
  }
  // Pass 2: visibility, feathering (which reject occluded cameras before any square root), the
  // penalties, and the best k + 1 kept in order.
  int count = 0;
  for (int k = 0; k < num_candidates; ++k) {
    const Candidate& candidate = candidates[k];
    const int i = candidate.camera;
    const BlendCamera& camera = cameras[i];
    const float px = candidate.px, py = candidate.py, map_x = candidate.map_x, map_y = candidate.map_y;
    // Shadow-map test against the farthest of the 4 surrounding depth texels (lenient on slanted
    // surfaces; occlusion edges are feathered anyway), feather from the nearest texel.
    const float depth = FarthestDepth(camera, map_x, map_y);
    if (!(depth > 0.0f) || candidate.z > depth + in.depth_bias) continue;
    const int tx = std::min(static_cast<int>(map_x), camera.map_width - 1);  // floor: map_x >= 0
    const int ty = std::min(static_cast<int>(map_y), camera.map_height - 1);
    const float feather = camera.depth_feather[2 * (static_cast<std::size_t>(ty) * camera.map_width + tx) + 1];
    if (!(feather > 0.0f)) continue;
    Eigen::Vector3f to_camera = camera.center - X;
    const float camera_distance = to_camera.norm();
    to_camera /= camera_distance;
    const float facing = n.dot(to_camera);
    if (!(facing > 0.0f)) continue;
    float q = Smoothstep(in.grazing_cos, facing) * feather;  // 1 when grazing_cos is 0 (off)
    if (!(q > 0.0f)) continue;
    // Angle between the rays: sqrt(2 - 2 cos) is the chord, within 5% of the angle below 60 deg.
    const float angle = std::sqrt(std::max(2.0f - 2.0f * to_view.dot(to_camera), 0.0f));
    float penalty = std::max(
        angle + in.resolution_weight * std::max(0.0f, camera_distance - view_distance) / view_distance, 1e-4f);
    ++count;
    float x = px, y = py;
    int c = i;
    for (int s = 0; s < slots; ++s) {  // insertion into the sorted slots
      if (penalty < slot_penalty[s]) {
        std::swap(penalty, slot_penalty[s]);
        std::swap(q, slot_quality[s]);
        std::swap(x, slot_x[s]);
        std::swap(y, slot_y[s]);
        std::swap(c, slot_camera[s]);
      }
    }
  }
  // Threshold t: the (k+1)-th smallest penalty, or pi when k or fewer cameras see X.
  const float threshold = count > in.best_k ? slot_penalty[in.best_k] : 3.14159265f;
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  float total = 0.0f;
  for (int s = 0; s < in.best_k; ++s) {
    if (!(slot_penalty[s] < threshold)) continue;
    const float w = (1.0f - slot_penalty[s] / threshold) / slot_penalty[s] * slot_quality[s];
    if (!(w > 0.0f)) continue;
    const BlendCamera& camera = cameras[slot_camera[s]];
    sum += w * Bilinear(camera, slot_x[s], slot_y[s]).cwiseProduct(camera.gain);
    total += w;
  }
  if (!(total > 0.0f)) return false;
  for (int c = 0; c < 3; ++c) out[c] = static_cast<std::uint8_t>(std::clamp(sum[c] / total, 0.0f, 255.0f) + 0.5f);
  return true;
}

}  // namespace confluent::render_internal
