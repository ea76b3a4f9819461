#include "silhouette/classify_kernel.h"

#include <cstdlib>

namespace confluent {

namespace {

// The loop, inlined into one function per instruction set. This file is compiled with
// -ffp-contract=off (silhouette/CMakeLists.txt): no variant fuses a multiply and an add, so
// every variant rounds exactly as ClassifyPixelReference does (vectorising a loop without
// reductions does not reorder its arithmetic). Products and sums of 8-bit values (norm_sq,
// dot, value_sq) are exact integers below 2^24 in any case.
__attribute__((always_inline)) inline void ClassifyLoop(const std::uint8_t* __restrict rgb, const ClassifyPlanes& model,
                                                        std::size_t count, const ClassifyParams& params,
                                                        std::uint8_t* __restrict mask) {
  const std::uint8_t* __restrict mean_r = model.mean_r;
  const std::uint8_t* __restrict mean_g = model.mean_g;
  const std::uint8_t* __restrict mean_b = model.mean_b;
  const std::uint8_t* __restrict spread = model.spread;
  const std::uint8_t* __restrict low_code = model.low;
  const std::uint8_t* __restrict high_code = model.high;
  const float tc2 = params.chroma_threshold_sq;
  const float tc2_rel2 = params.chroma_threshold_sq * params.chroma_relative_sq;
  const float step2 = params.spread_step * params.spread_step;
  const float low_scale = 1.0f / 255.0f;
  const float high_step = params.high_step;
  // Branch-free, planar model bytes: the compiler vectorises it. The same operations in the
  // same order as ClassifyPixelReference.
  for (std::size_t i = 0; i < count; ++i) {
    const float r = rgb[3 * i], g = rgb[3 * i + 1], b = rgb[3 * i + 2];
    const float mr = mean_r[i], mg = mean_g[i], mb = mean_b[i];
    const float s = spread[i];
    const float low = low_code[i] * low_scale;
    const float high = 1.0f + high_code[i] * high_step;
    const float norm_sq = mr * mr + mg * mg + mb * mb;
    const float dot = r * mr + g * mg + b * mb;
    const float value_sq = r * r + g * g + b * b;
    const float dot_sq = dot * dot;
    const bool chroma = value_sq * norm_sq - dot_sq > tc2 * step2 * s * s * norm_sq + tc2_rel2 * dot_sq;
    const bool dark = dot < low * norm_sq;
    const bool bright = dot > high * norm_sq;
    mask[i] = (chroma | dark | bright) ? 255 : 0;
  }
}

void ClassifyBaseline(const std::uint8_t* rgb, const ClassifyPlanes& model, std::size_t count,
                      const ClassifyParams& params, std::uint8_t* mask) {
  ClassifyLoop(rgb, model, count, params, mask);
}

#if defined(__x86_64__) || defined(__i386__)
#define CONFLUENT_CLASSIFY_X86 1
__attribute__((target("avx2"))) void ClassifyAvx2(const std::uint8_t* rgb, const ClassifyPlanes& model,
                                                  std::size_t count, const ClassifyParams& params,
                                                  std::uint8_t* mask) {
  ClassifyLoop(rgb, model, count, params, mask);
}

__attribute__((target("avx512f,avx512bw,avx512vl"))) void ClassifyAvx512(const std::uint8_t* rgb,
                                                                         const ClassifyPlanes& model,
                                                                         std::size_t count,
                                                                         const ClassifyParams& params,
                                                                         std::uint8_t* mask) {
  ClassifyLoop(rgb, model, count, params, mask);
}
#endif

}  // namespace

bool ClassifyIsaSupported(ClassifyIsa isa) {
  switch (isa) {
    case ClassifyIsa::kBaseline: return true;
#ifdef CONFLUENT_CLASSIFY_X86
    case ClassifyIsa::kAvx2: return __builtin_cpu_supports("avx2");
    case ClassifyIsa::kAvx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
             __builtin_cpu_supports("avx512vl");
#else
    default: return false;
#endif
  }
  return false;
}

void ClassifyPixels(const std::uint8_t* rgb, const ClassifyPlanes& model, std::size_t count,
                    const ClassifyParams& params, std::uint8_t* mask, ClassifyIsa isa) {
  if (!ClassifyIsaSupported(isa)) std::abort();
  switch (isa) {
    case ClassifyIsa::kBaseline: ClassifyBaseline(rgb, model, count, params, mask); return;
#ifdef CONFLUENT_CLASSIFY_X86
    case ClassifyIsa::kAvx2: ClassifyAvx2(rgb, model, count, params, mask); return;
    case ClassifyIsa::kAvx512: ClassifyAvx512(rgb, model, count, params, mask); return;
#else
    default: return;
#endif
  }
}

void ClassifyPixels(const std::uint8_t* rgb, const ClassifyPlanes& model, std::size_t count,
                    const ClassifyParams& params, std::uint8_t* mask) {
  const ClassifyIsa isa = ClassifyIsaSupported(ClassifyIsa::kAvx512) ? ClassifyIsa::kAvx512
                          : ClassifyIsaSupported(ClassifyIsa::kAvx2) ? ClassifyIsa::kAvx2
                                                                     : ClassifyIsa::kBaseline;
  ClassifyPixels(rgb, model, count, params, mask, isa);
}

bool ClassifyPixelReference(const std::uint8_t rgb[3], const std::uint8_t mean[3], std::uint8_t spread,
                            std::uint8_t low_code, std::uint8_t high_code, const ClassifyParams& params) {
  const float r = rgb[0], g = rgb[1], b = rgb[2];
  const float mr = mean[0], mg = mean[1], mb = mean[2];
  const float s = spread;
  const float low = low_code * (1.0f / 255.0f);
  const float high = 1.0f + high_code * params.high_step;
  const float norm_sq = mr * mr + mg * mg + mb * mb;
  const float dot = r * mr + g * mg + b * mb;
  const float value_sq = r * r + g * g + b * b;
  const float dot_sq = dot * dot;
  const float tc2 = params.chroma_threshold_sq;
  const float tc2_rel2 = params.chroma_threshold_sq * params.chroma_relative_sq;
  const float step2 = params.spread_step * params.spread_step;
  // |I|^2 |mu|^2 - (I.mu)^2 = |mu|^2 CD^2, against tau^2 (sigma^2 + rel^2 alpha^2 |mu|^2) |mu|^2.
  const bool chroma = value_sq * norm_sq - dot_sq > tc2 * step2 * s * s * norm_sq + tc2_rel2 * dot_sq;
  return chroma || dot < low * norm_sq || dot > high * norm_sq;
}

}  // namespace confluent
