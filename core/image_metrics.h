#pragma once
// Image-quality metrics restricted to a region: PSNR and SSIM inside a mask, and the masks they
// are usually computed in (the union of a real and a rendered silhouette).
//
// Convention. Both images are compared on their first three channels (one for grey images),
// with values scaled to [0, 1] (8-bit / 255, 16-bit / 65535, float as is). A pixel counts when
// its mask value is non-zero; an empty mask means the whole image.

#include "core/image.h"

namespace confluent {

// Peak signal-to-noise ratio (dB, peak 1) over the masked pixels. Identical images give
// kMaxPsnrDb. Throws std::invalid_argument for images of different sizes or channel counts, a
// mask of another size, or a mask without any set pixel.
double MaskedPsnr(const Image& a, const Image& b, const Image& mask = {});

// The PSNR reported for identical images (instead of infinity).
constexpr double kMaxPsnrDb = 100.0;

// Mean structural similarity (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5, K1 0.01,
// K2 0.03) of the luma (Rec. 601 weights) over the masked pixels. The window statistics use the
// whole image, so the background next to the mask edge takes part as it does in a full-image
// SSIM. Same errors as MaskedPsnr.
double MaskedSsim(const Image& a, const Image& b, const Image& mask = {});

// The union of two 1-channel masks of the same size (0/255). Throws std::invalid_argument when
// the sizes differ.
Image UnionMask(const Image& a, const Image& b);

// Per-pixel absolute difference of the first three channels, averaged, as a 1-channel float
// image in [0, 1] (for error heat maps). Same size rules as MaskedPsnr.
Image AbsoluteDifference(const Image& a, const Image& b);

}  // namespace confluent
