#include "app/tracking_args.h"

#include "core/error.h"

namespace confluent::app {

OptionSpec GirthInflationOptionSpec() {
  return {"girth-inflation", "F",
          "after the first frame's fit, try every girth grown by up to F (e.g. 0.1) and keep the growth that "
          "overlaps the tracking cameras best: loose clothes, rigs whose cameras disagree by pixels (default: up to 0.1, "
          "only when the first frame's fit leaves the tracking cameras' IoU below 0.91; 0 = never)"};
}

std::optional<double> GirthInflationFromArgs(const ParsedArgs& args) {
  if (!args.has("girth-inflation")) return std::nullopt;
  const double fraction = args.get_double("girth-inflation", 0.0);
  if (!(fraction >= 0.0 && fraction <= 0.5)) throw UsageError("--girth-inflation: must be within [0, 0.5]");
  return fraction;
}

OptionSpec ShapeSamplesOptionSpec() {
  return {"shape-samples", "N",
          "learn the body's shape from the first frame and every 5th after it, N frames in all (the frames "
          "after the first are tracked ahead once for it; default 6; 0 or 1 = the first frame's shape alone)"};
}

std::optional<int> ShapeSamplesFromArgs(const ParsedArgs& args) {
  if (!args.has("shape-samples")) return std::nullopt;
  const int samples = args.get_int("shape-samples", 0);
  if (samples < 0 || samples > 50) throw UsageError("--shape-samples: must be within [0, 50]");
  return samples;
}

OptionSpec FitDownscaleOptionSpec() {
  return {"downscale", "N",
          "mask reduction for fitting (default 0 = automatic: the first frame about 256 px across, "
          "tracking about 512)"};
}

std::optional<int> FitDownscaleFromArgs(const ParsedArgs& args) {
  if (!args.has("downscale")) return std::nullopt;
  const int factor = args.get_int("downscale", 0);
  if (factor < 0 || factor > 16) throw UsageError("--downscale: must be within [0, 16]");
  return factor;
}

}  // namespace confluent::app
