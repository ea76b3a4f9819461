#include "tracking/skirt_search.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "core/error.h"

namespace confluent {

void SkirtSearchOptions::Check(const std::string& owner) const {
  RequireOption(length_step_m > 0, owner + "length_step_m", length_step_m, "> 0");
  RequireOption(flare_step_m > 0, owner + "flare_step_m", flare_step_m, "> 0");
  RequireOption(min_length_m > 0, owner + "min_length_m", min_length_m, "> 0");
  RequireOption(refinements >= 0 && refinements <= 8, owner + "refinements", refinements, "in [0, 8]");
  RequireOption(min_gain >= 0 && min_gain < 1, owner + "min_gain", min_gain, "in [0, 1)");
}

SkirtSearchResult SearchSkirt(const BodyShape& shape, const SkirtSearchOptions& options,
                              const std::function<double(const BodyShape&)>& overlap) {
  options.Check("SkirtSearchOptions.");
  if (!(shape.skirt_length_m > 0.0)) throw std::invalid_argument("SearchSkirt: the shape has no skirt");
  // The fit's bounds, from the scales of the shape group it takes them from (the head's alone).
  const int head = static_cast<int>(BodySegment::kHead);
  // Plain variables, not a structured binding: C++17 lambdas cannot capture those (clang refuses).
  const std::array<double, 2> max_skirt = MaxSkirt(shape.length_scale[head], shape.girth_scale[head]);
  const double max_length = max_skirt[0], max_flare = max_skirt[1];

  SkirtSearchResult result;
  result.shape = shape;
  result.overlap = overlap(shape);
  result.evaluations = 1;
  const double fitted_overlap = result.overlap;
  BodyShape best = shape;
  double best_overlap = result.overlap;
  auto try_skirt = [&](double length, double flare) {
    if (length < options.min_length_m - 1e-9 || length > max_length + 1e-9 || flare < -1e-9 || flare > max_flare + 1e-9)
      return;
    BodyShape candidate = shape;
    candidate.skirt_length_m = length;
    candidate.skirt_flare_m = std::max(flare, 0.0);
    const double value = overlap(candidate);
    ++result.evaluations;
    if (value > best_overlap) {
      best_overlap = value;
      best = candidate;
    }
  };
  for (double length = options.min_length_m; length <= max_length + 1e-9; length += options.length_step_m)
    for (double flare = 0.0; flare <= max_flare + 1e-9; flare += options.flare_step_m) try_skirt(length, flare);
  double length_step = options.length_step_m, flare_step = options.flare_step_m;
  for (int round = 0; round < options.refinements; ++round) {
    length_step *= 0.5;
    flare_step *= 0.5;
    const double centre_length = best.skirt_length_m, centre_flare = best.skirt_flare_m;
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j)
        if (i != 0 || j != 0) try_skirt(centre_length + i * length_step, centre_flare + j * flare_step);
  }
  if (best_overlap >= fitted_overlap + options.min_gain) {
    result.shape = best;
    result.overlap = best_overlap;
    result.changed = true;
  }
  return result;
}

}  // namespace confluent
