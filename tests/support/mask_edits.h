#pragma once
// Masks made deliberately wrong for tests: a camera's mask moved off the calibration.

#include <cstdint>

#include "core/image.h"

namespace confluent::testing {

// `mask` (1-channel) moved right by `dx` pixels; what enters from the left is background.
inline Image ShiftedMask(const Image& mask, int dx) {
  Image out(mask.width, mask.height, 1);
  for (int y = 0; y < mask.height; ++y)
    for (int x = 0; x < mask.width; ++x)
      if (x - dx >= 0 && x - dx < mask.width) out.at<std::uint8_t>(x, y) = mask.at<std::uint8_t>(x - dx, y);
  return out;
}

}  // namespace confluent::testing
