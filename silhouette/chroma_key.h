#pragma once
// Green-screen keying: a pixel is screen when its green exceeds both red and blue by a margin
// that grows with its green level. Spill (green light reflected onto the actor's edges) only
// adds a little green, far below the screen's, so a ratio threshold between the two modes
// keeps it foreground.

#include "core/image.h"

namespace confluent {

// Settings of ChromaKey.
struct ChromaKeyOptions {
  // Screen when (g - max(r, b)) > greenness * g + min_margin. 0 = choose per camera as
  // screen_fraction times the screen's median greenness, within [auto_min_greenness,
  // auto_max_greenness].
  double greenness = 0.0;
  double screen_fraction = 0.4;
  double auto_min_greenness = 0.08;
  double auto_max_greenness = 0.3;
  // Extra margin in grey levels, so that noise on dark grey pixels is not taken for screen.
  double min_margin = 3.0;
  // Auto method detection: a frame is a green screen when at least this fraction of its
  // pixels is clearly green (greenness above 0.2 and green above 30 levels).
  double detect_fraction = 0.35;
  // Throws UsageError naming the bad field.
  void Check() const;
};

// Greenness threshold for an 8-bit RGB frame: options.greenness when set, else a fraction of
// the median greenness (g - max(r, b)) / g of its clearly green pixels, clamped to the options'
// auto range.
double ChooseGreenness(const Image& frame, const ChromaKeyOptions& options);

// Foreground mask (0/255, 1 channel) of an 8-bit RGB frame keyed against a green screen with
// the given greenness threshold.
Image ChromaKey(const Image& frame, double greenness, const ChromaKeyOptions& options);

// Fraction of an 8-bit RGB frame's pixels that are clearly screen green.
double GreenFraction(const Image& frame);

// True when `frame` looks like a green-screen shot (GreenFraction >= options.detect_fraction).
bool LooksLikeGreenScreen(const Image& frame, const ChromaKeyOptions& options);

}  // namespace confluent
