#include "silhouette/chroma_key.h"

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/error.h"

namespace confluent {

void ChromaKeyOptions::Check() const {
  const std::string owner = "ChromaKeyOptions.";
  RequireOption(greenness >= 0 && greenness < 1, owner + "greenness", greenness, "in [0, 1) (0 = automatic)");
  RequireOptions(auto_min_greenness > 0 && auto_min_greenness <= auto_max_greenness && auto_max_greenness < 1,
                 owner + "auto_min_greenness", auto_min_greenness, owner + "auto_max_greenness", auto_max_greenness,
                 "0 < auto_min_greenness <= auto_max_greenness < 1");
  RequireOption(screen_fraction > 0 && screen_fraction < 1, owner + "screen_fraction", screen_fraction, "in (0, 1)");
  RequireOption(min_margin >= 0 && min_margin <= 100, owner + "min_margin", min_margin, "in [0, 100] grey levels");
  RequireOption(detect_fraction > 0 && detect_fraction <= 1, owner + "detect_fraction", detect_fraction, "in (0, 1]");
}

namespace {

void CheckFrame(const Image& frame) {
  if (frame.channels != 3 || frame.type != PixelType::kUInt8) std::abort();  // callers convert to RGB8
}

}  // namespace

double ChooseGreenness(const Image& frame, const ChromaKeyOptions& options) {
  if (options.greenness > 0) return options.greenness;
  CheckFrame(frame);
  // Median greenness (g - max(r, b)) / g of the clearly green pixels: the screen's own
  // greenness, which folds and shading do not change (it is a ratio).
  std::vector<float> screen;
  const std::size_t pixels = static_cast<std::size_t>(frame.width) * frame.height;
  const std::uint8_t* p = frame.data.data();
  for (std::size_t i = 0; i < pixels; i += 3) {
    const int r = p[3 * i], g = p[3 * i + 1], b = p[3 * i + 2];
    if (g > 30 && (g - std::max(r, b)) * 5 > g) screen.push_back(static_cast<float>(g - std::max(r, b)) / g);
  }
  double threshold = options.auto_max_greenness;
  if (!screen.empty()) {
    auto middle = screen.begin() + screen.size() / 2;
    std::nth_element(screen.begin(), middle, screen.end());
    threshold = options.screen_fraction * *middle;
  }
  return std::clamp(threshold, options.auto_min_greenness, options.auto_max_greenness);
}

Image ChromaKey(const Image& frame, double greenness, const ChromaKeyOptions& options) {
  CheckFrame(frame);
  Image mask(frame.width, frame.height, 1);
  const std::size_t pixels = static_cast<std::size_t>(frame.width) * frame.height;
  const std::uint8_t* __restrict p = frame.data.data();
  std::uint8_t* __restrict out = mask.data.data();
  // Fixed point: the threshold in 1/256 units, the margin in 1/256 levels.
  const int ratio = static_cast<int>(greenness * 256.0 + 0.5);
  const int margin = static_cast<int>(options.min_margin * 256.0 + 0.5);
  for (std::size_t i = 0; i < pixels; ++i) {
    const int r = p[3 * i], g = p[3 * i + 1], b = p[3 * i + 2];
    const int excess = (g - std::max(r, b)) * 256;
    out[i] = excess > ratio * g + margin ? 0 : 255;
  }
  return mask;
}

double GreenFraction(const Image& frame) {
  CheckFrame(frame);
  const std::size_t pixels = static_cast<std::size_t>(frame.width) * frame.height;
  if (pixels == 0) return 0.0;
  const std::uint8_t* p = frame.data.data();
  std::size_t green = 0, seen = 0;
  for (std::size_t i = 0; i < pixels; i += 7, ++seen) {
    const int r = p[3 * i], g = p[3 * i + 1], b = p[3 * i + 2];
    if (g > 30 && (g - std::max(r, b)) * 5 > g) ++green;
  }
  return static_cast<double>(green) / static_cast<double>(seen);
}

bool LooksLikeGreenScreen(const Image& frame, const ChromaKeyOptions& options) {
  return GreenFraction(frame) >= options.detect_fraction;
}

}  // namespace confluent
