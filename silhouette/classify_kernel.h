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

// The packed background model, one byte per pixel in each of six planes.
struct ClassifyPlanes {
  const std::uint8_t* mean_r = nullptr;  // mean colour, 8-bit (at least 1)
  const std::uint8_t* mean_g = nullptr;
  const std::uint8_t* mean_b = nullptr;
  const std::uint8_t* spread = nullptr;  // spread code: spread = code * spread_step grey levels
  const std::uint8_t* low = nullptr;     // low brightness bound * 255
  const std::uint8_t* high = nullptr;    // (high brightness bound - 1) / high_step
};

// The six planes of a model stored one after another in `packed` (pixels bytes each, in the
// order of ClassifyPlanes' fields).
inline ClassifyPlanes PlanesOf(const std::uint8_t* packed, std::size_t pixels) {
  ClassifyPlanes planes;
  planes.mean_r = packed;
  planes.mean_g = planes.mean_r + pixels;
  planes.mean_b = planes.mean_g + pixels;
  planes.spread = planes.mean_b + pixels;
  planes.low = planes.spread + pixels;
  planes.high = planes.low + pixels;
  return planes;
}

// Instruction sets the classification loop is compiled for.
enum class ClassifyIsa { kBaseline, kAvx2, kAvx512 };

// Whether this CPU runs `isa`.
bool ClassifyIsaSupported(ClassifyIsa isa);

// For `count` pixels: `rgb` 3 bytes each, the model's planes; writes 255 (foreground) or 0 to
// `mask`, with the widest instruction set this CPU has. Every variant gives the same bits as
// ClassifyPixelReference.
void ClassifyPixels(const std::uint8_t* rgb, const ClassifyPlanes& model, std::size_t count,
                    const ClassifyParams& params, std::uint8_t* mask);
// As above with the given variant (tests); aborts if the CPU does not support it.
void ClassifyPixels(const std::uint8_t* rgb, const ClassifyPlanes& model, std::size_t count,
                    const ClassifyParams& params, std::uint8_t* mask, ClassifyIsa isa);

// The classification of one pixel, written plainly: the definition the kernels follow (same
// operations in the same order, so the same bits). `mean` is R G B; true for foreground.
bool ClassifyPixelReference(const std::uint8_t rgb[3], const std::uint8_t mean[3], std::uint8_t spread,
                            std::uint8_t low_code, std::uint8_t high_code, const ClassifyParams& params);

}  // namespace confluent
