#pragma once
// Boundary refinement of a mask by a graph cut on colour models of the actor and of its
// surroundings (OpenCV's grabCut, Rother et al. 2004), seeded by the mask and the other
// cameras' hull: removes background-coloured rims (ghosts of where the actor was) and fills
// actor-coloured gaps.

#include "core/image.h"
#include "silhouette/background_model.h"

namespace confluent {

struct GrabCutRefineOptions {
  int iterations = 2;
  // Pixels farther than this from both the mask and the hull are certain background; mask pixels
  // this deep inside both the mask and the hull are certain foreground (per 1000 pixels of width).
  double band = 30.0;
  double core = 25.0;
  // When the cut's mask covers less of the hull than its input did, by more than this fraction
  // of the hull, it is cut again with the hull eroded by `retry_core` (per 1000 pixels of width)
  // as certain foreground as well; 1 = never. Samba and the modern dance lose an upper body or
  // the legs in a frame by 0.25-0.45; ordinary cuts of ghosts (the builtin capture) by at most 0.22.
  double retry_drop = 0.23;
  double retry_core = 12.5;
  // Throws UsageError naming the bad field.
  void Check() const;
};

// Refines `mask` (1-channel 0/255) of the 8-bit RGB `frame`; `hull` (the others' projected hull,
// same size, or empty) widens the uncertain band and must contain the certain foreground;
// `sure` (same size, or empty) is certain foreground too (a person prior's core).
// Returns the mask unchanged when it is empty.
Image RefineMaskGrabCut(const Image& frame, const Image& mask, const Image& hull, const GrabCutRefineOptions& options,
                        const Image& sure = Image());

// Takes back from `refined` what the cut added to `mask` (in `refined`, not in `mask`) outside
// `hull` (the others' strict hull, or empty: nothing taken back) where `model` sees its own
// background in `frame` (8-bit RGB; class kBackground, not a shadow or highlight): a poster in
// the shirt's colours beside the body, which a background learned without a plate knows.
// Returns the pixels taken back. Throws UsageError when the sizes differ.
int TakeBackKnownBackground(Image* refined, const Image& mask, const Image& frame, const BackgroundModel& model,
                            const Image& hull);

}  // namespace confluent
