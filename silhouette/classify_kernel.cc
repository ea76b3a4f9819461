#include "silhouette/classify_kernel.h"

namespace confluent {

__attribute__((target_clones("avx2", "default")))
void ClassifyPixels(const std::uint8_t* __restrict rgb, const std::uint8_t* __restrict packed, std::size_t count,
                    const ClassifyParams& params, std::uint8_t* __restrict mask) {
  const float tc2 = params.chroma_threshold_sq;
  const float tc2_rel2 = params.chroma_threshold_sq * params.chroma_relative_sq;
  const float step2 = params.spread_step * params.spread_step;
  const float low_scale = 1.0f / 255.0f;
  const float high_step = params.high_step;
  // A plain branch-free loop that the compiler vectorises.
  for (std::size_t i = 0; i < count; ++i) {
    const float r = rgb[3 * i], g = rgb[3 * i + 1], b = rgb[3 * i + 2];
    const float mr = packed[8 * i], mg = packed[8 * i + 1], mb = packed[8 * i + 2];
    const float s = packed[8 * i + 3];
    const float low = packed[8 * i + 4] * low_scale;
    const float high = 1.0f + packed[8 * i + 5] * high_step;
    const float norm_sq = mr * mr + mg * mg + mb * mb;
    const float dot = r * mr + g * mg + b * mb;
    const float value_sq = r * r + g * g + b * b;
    const float dot_sq = dot * dot;
    // |I|^2 |mu|^2 - (I.mu)^2 = |mu|^2 CD^2, against tau^2 (sigma^2 + rel^2 alpha^2 |mu|^2) |mu|^2.
    const bool chroma = value_sq * norm_sq - dot_sq > tc2 * step2 * s * s * norm_sq + tc2_rel2 * dot_sq;
    const bool dark = dot < low * norm_sq;
    const bool bright = dot > high * norm_sq;
    mask[i] = (chroma | dark | bright) ? 255 : 0;
  }
}

}  // namespace confluent
