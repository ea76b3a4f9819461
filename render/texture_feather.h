#pragma once
// Feather maps of projective texturing (render/projective_texture.h): per input camera, its depth
// map interleaved with a feather weight that falls to 0 at the mesh outline, at depth
// discontinuities and at the mask outline. Internal to render/.

#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/image.h"
#include "render/cpu_raster.h"
#include "render/projective_texture.h"

namespace confluent::render_internal {

// 0 at x <= 0, 1 at x >= edge (and 1 everywhere when edge <= 0), smooth (3t^2 - 2t^3) between.
inline float Smoothstep(float edge, float x) {
  if (edge <= 0.0f) return 1.0f;
  const float t = std::clamp(x / edge, 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// Buffers of DepthFeatherMap, kept across frames (large fresh allocations fault in every page).
struct FeatherScratch {
  std::vector<float> padded;
  std::vector<std::uint8_t> padded_mask, not_edge, column;
  std::vector<std::int32_t> squared_distance, row32, best32;
  std::vector<std::int16_t> row16, best16;
};

// Depth and feather map of one camera, interleaved into `out` (2 floats per pixel, w x h):
// camera z (0 = not covered) and smoothstep(0, feather_px, distance to the nearest outline pixel
// of the mesh, depth discontinuity or mask outline), 0 outside the mesh or the mask; feather_px in
// map pixels. `z` may be nonzero only inside `z_box`. `out` is zero outside *written (the region
// the previous call wrote), and only the region around the covered pixels is rewritten; *written
// becomes that region. Returns the number of covered pixels. Thread-safe (reads only its
// arguments, writes only `out`, *written and *scratch).
int DepthFeatherMap(const float* z, int w, int h, const PixelBox& z_box, const Image& mask,
                    const ProjectiveTextureOptions& options, double feather_px, float* out, PixelBox* written,
                    FeatherScratch* scratch);

}  // namespace confluent::render_internal
