#pragma once
// The tracker options that `confluent run` and `confluent track` share.

#include <optional>

#include "app/command_line.h"

namespace confluent::app {

// --girth-inflation F.
OptionSpec GirthInflationOptionSpec();

// --girth-inflation's fraction (TrackerOptions::InflateGirthsAlways); empty when absent (the
// tracker's automatic default). Throws UsageError outside [0, 0.5].
std::optional<double> GirthInflationFromArgs(const ParsedArgs& args);

// --shape-samples N.
OptionSpec ShapeSamplesOptionSpec();

// --shape-samples's count (TrackerOptions::shape_samples); empty when absent. Throws UsageError
// outside [0, 50].
std::optional<int> ShapeSamplesFromArgs(const ParsedArgs& args);

// --downscale N.
OptionSpec FitDownscaleOptionSpec();

// --downscale's factor (SilhouetteFitOptions::downscale); empty when absent (automatic). Throws
// UsageError outside [0, 16].
std::optional<int> FitDownscaleFromArgs(const ParsedArgs& args);

}  // namespace confluent::app
