#pragma once
// INTERNAL to silhouette/: the per-pixel Horprasert classification loop, kept separate so that
// it can be compiled for several instruction sets.

#include <cstddef>
#include <cstdint>

namespace confluent {

// Constants of one classification (see BackgroundModel::Pack for the packed layout).
struct ClassifyParams {
  float chroma_threshold_sq = 20.25f;  // (chromaticity threshold in spreads)^2
  float chroma_relative_sq = 1e-4f;    // (relative chromaticity tolerance)^2
  float spread_step = 0.125f;          // grey levels per spread code
  float high_step = 1.0f / 32.0f;      // high-brightness bound = 1 + code * high_step
};

// For `count` pixels: `rgb` 3 bytes each, `packed` 8 bytes each (mean R G B, spread code, low
// bound * 255, (high bound - 1) / high_step, 2 unused); writes 255 (foreground) or 0 to `mask`.
void ClassifyPixels(const std::uint8_t* rgb, const std::uint8_t* packed, std::size_t count,
                    const ClassifyParams& params, std::uint8_t* mask);

}  // namespace confluent
