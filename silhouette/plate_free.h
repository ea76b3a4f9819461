#pragma once
// Backgrounds learned from the video itself when there is no clean plate, for every camera of a
// calibrated rig together: per-pixel statistics over the frames where the pixel is free, the
// occupancy coming from the masks and from the visual hulls of the other cameras, iterated.
// Robust to an actor who stays in place: where the temporal median holds the actor, the first
// estimate is the surrounding background filled in (inpainted) and the samples nearest to it.
// A pixel that the occupancy never leaves free takes the background inpainted around it; with a
// person prior, the colour that keeps coming back in the samples where the geometry alone (the
// others' strict hull) leaves it free, if any (a poster behind the actor, shown whenever they
// step aside).

#include <string>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "silhouette/background_model.h"
#include "silhouette/mask_cleanup.h"
#include "silhouette/multiview.h"
#include "silhouette/person_prior.h"

namespace confluent {

// Settings of LearnBackgroundsWithoutPlates.
struct PlateFreeOptions {
  // Rounds of masks -> multi-view correction -> occupancy -> background.
  int iterations = 2;
  // Occupancy is the corrected mask and the others' hulls (tolerant and strict), grown by this
  // margin (per 1000 pixels of image width).
  double occupancy_margin = 10.0;
  // The occupancy also takes what lies below the hull down to the floor (z = 0): the legs of a
  // performer who hardly moves, whom the masks find only where they move.
  bool columns_to_floor = true;
  // And what lies above the hull's top: the columns whose highest voxel is within
  // `head_room_near_top_m` of the hull's highest, continued `head_room_m` upwards (0 = off). A
  // performer who hardly moves keeps their head in every camera's first background, so that
  // the masks lose it and the hull ends at the shoulders.
  double head_room_m = 0.30;
  double head_room_near_top_m = 0.25;
  // A pixel the actor may cover (its samples differ from the median) takes the samples within
  // this many noise sigmas (plus 4% of the colour's brightness) of the nearest sample to the
  // inpainted background.
  double nearest_tolerance = 4.0;
  // From the second estimate on, colour histograms of the actor and of the background decide
  // too: a sample whose colour is background with at least this probability is free even under
  // the occupancy (a ghost's true background), one that is the actor's with it never is.
  double background_colour = 0.9;
  // With a person prior, a pixel that the occupancy never leaves free (a poster behind the actor,
  // which the prior and the masks take for the actor) takes the samples where the geometry alone
  // leaves it free (outside the others' strict hull), when at least this many of them agree on
  // one colour (within nearest_tolerance): a still background seen between the actor's moves.
  // 0 = off.
  int stable_free_samples = 3;
  MultiViewOptions multiview;
  // Throws UsageError naming the bad field.
  void Check() const;
};

// `frames[c]` are the sampled frames of camera c (8-bit RGB, the same instants for every
// camera, at least 3). `models[c]` holds a model already known (a plate) that is kept, or an
// empty model for a camera to learn; cameras with an empty `frames[c]` are left out. Returns
// the models; `notes` receives one line per camera learned. Work is spread over up to `threads`
// threads; the result does not depend on their number. With `people` (`(*people)[c][k]`: where
// a person prior, silhouette/person_prior.h, found the actor in camera c's sampled frame k; no
// regions for a camera without), the actor's samples are
// those of the person's regions, and the occupancy and masks are kept within reach of them (a
// region with nobody found leaves that frame to the other cameras alone).
std::vector<BackgroundModel> LearnBackgroundsWithoutPlates(const Rig& rig, const std::vector<std::vector<Image>>& frames,
                                                           std::vector<BackgroundModel> models,
                                                           const BackgroundModelOptions& background,
                                                           const MaskCleanupOptions& cleanup,
                                                           const PlateFreeOptions& options,
                                                           std::vector<std::string>* notes = nullptr,
                                                           int threads = 1,
                                                           const std::vector<std::vector<PersonRegion>>* people = nullptr);

}  // namespace confluent
