#pragma once
// Morphological clean-up of a raw foreground mask: speckle removal, closing, keeping the
// actor's connected components, and filling small holes. Component analysis runs at a reduced
// resolution, on runs of pixels and inside the foreground's bounding box (the result is that of
// whole-frame morphology and labelling); the mask's edge stays the full-resolution
// classification.

#include "core/image.h"

namespace confluent {

// Settings of CleanMask.
struct MaskCleanupOptions {
  // Components, opening, closing and holes are computed at 1/work_scale of the resolution
  // (1, 2 or 4; 0 = automatic: 1 up to 640 pixels wide, 2 up to 2048, else 4); a work pixel is
  // foreground when at least half of its block (cut at the right and bottom edges) is. The
  // boundary band is taken from the full-resolution mask.
  int work_scale = 0;
  // Opening radius, in work pixels: removes speckle touching the actor and thin bridges, but
  // also limbs thinner than twice the radius; 0 = none (isolated speckle is dropped anyway).
  int open_radius_px = 0;
  // Closing radius applied to the mask's shape (fills cracks, but also concave corners such as
  // armpits), in work pixels; 0 = none.
  int close_radius_px = 0;
  // Closing radius used only to decide which pieces belong together (the mask is not changed
  // by it), in work pixels.
  int connect_radius_px = 3;
  // Components smaller than this fraction of the largest one are dropped as speckle...
  double min_part_fraction = 0.01;
  // ...and so are those farther than this fraction of the largest component's bounding-box
  // diagonal from that box (a hand briefly disconnected from the arm stays).
  double max_part_distance_fraction = 0.25;
  // Holes (background regions enclosed by the actor) up to this fraction of the actor's area
  // are filled; larger ones (a gap between arm and body) stay.
  double max_hole_fraction = 0.005;
  // Throws UsageError naming the bad field.
  void Check() const;
};

// What CleanMask kept.
struct MaskCleanupStats {
  int parts_kept = 0;      // connected components kept (0 for an empty mask)
  int parts_dropped = 0;   // components dropped as speckle or far away
  int holes_filled = 0;
};

// Cleans `raw` (1-channel 8-bit, 0/255) and returns the cleaned mask of the same size.
Image CleanMask(const Image& raw, const MaskCleanupOptions& options, MaskCleanupStats* stats = nullptr);

}  // namespace confluent
