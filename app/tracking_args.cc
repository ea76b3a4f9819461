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

}  // namespace confluent::app
