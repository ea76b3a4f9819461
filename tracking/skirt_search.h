#pragma once
// The skirt's length and flare chosen by overlap, on a grid: the silhouette fit keeps the template
// inside the masks, so a dress that flares on some sides only (samba's) is fitted as a long
// straight tube, a local optimum that the overlap of a shorter, flared skirt beats.

#include <functional>
#include <string>

#include "tracking/body_template.h"

namespace confluent {

struct SkirtSearchOptions {
  bool enabled = true;
  // The coarse grid: lengths from min_length_m and flares from 0 to the fit's bounds (MaxSkirt),
  // in these steps; then `refinements` grids of half the last steps around the best so far.
  double length_step_m = 0.1;
  double flare_step_m = 0.04;
  double min_length_m = 0.2;
  int refinements = 2;
  // A skirt is changed only when its overlap beats the fitted one's by this much.
  double min_gain = 0.003;
  void Check(const std::string& owner) const;
};

struct SkirtSearchResult {
  BodyShape shape;         // `shape` with the best skirt found (the input's when none beats it)
  double overlap = 0.0;    // its overlap
  int evaluations = 0;     // overlaps computed
  bool changed = false;    // the skirt was changed
};

// Searches the skirt of `shape` (which must have one: skirt_length_m > 0) for the highest
// `overlap` (e.g. the mean IoU of the posed template with the masks).
SkirtSearchResult SearchSkirt(const BodyShape& shape, const SkirtSearchOptions& options,
                              const std::function<double(const BodyShape&)>& overlap);

}  // namespace confluent
