#pragma once
// Feet on a floor of their own darkness: the graph cut (silhouette/grabcut_refine.h) takes the
// other cameras' strict hull as its prior, and that hull has no feet where most cameras lose dark
// shoes against the floor and its shadow. Below the hull's lowest voxels, pixels that the
// background model calls foreground and whose colour points elsewhere than the background's
// (a shoe, not a shadow: a shadow darkens the floor's colour without turning it) are put back.

#include "calib/camera.h"
#include "calib/rig_check.h"
#include "core/image.h"
#include "silhouette/background_model.h"

namespace confluent {

struct FeetRestoreOptions {
  bool enabled = true;
  // Only the columns below hull voxels at most this high above the floor (z = 0), in metres.
  double max_height_m = 0.10;
  // A pixel is put back only when the angle between its RGB vector and the background's mean
  // colour is larger than this (degrees): a shadow keeps the floor's direction.
  double min_chroma_angle_deg = 8.0;
  // The columns are widened by this (pixels per 1000 pixels of image width): a shoe reaches
  // beyond the ankle's column to the toes.
  double reach = 10.0;
  // Throws UsageError naming the bad field.
  void Check() const;
};

// Adds to `mask` (1-channel 0/255 of `camera`) the pixels of `frame` (8-bit RGB) in the columns
// from `underside`'s low voxels down to the floor (ProjectColumnsToFloor, widened by
// options.reach) that `model` (of the frame's size) classes as foreground and whose colour
// differs in direction from the model's mean. Returns the number of pixels added (0 when
// disabled). Throws UsageError when the sizes differ.
int RestoreFeetBelowHull(Image* mask, const Image& frame, const Camera& camera, const HullUnderside& underside,
                         const BackgroundModel& model, const FeetRestoreOptions& options);

}  // namespace confluent
