#include "app/tracking_args.h"

#include "core/error.h"

namespace confluent::app {

OptionSpec GirthInflationOptionSpec() {
  return {"girth-inflation", "F",
          "after the first frame's fit, try every girth grown by up to F (e.g. 0.1) and keep the growth that "
          "overlaps the tracking cameras best: loose clothes, rigs whose cameras disagree by pixels (default 0 = off)"};
}

double GirthInflationFromArgs(const ParsedArgs& args) {
  const double fraction = args.get_double("girth-inflation", 0.0);
  if (!(fraction >= 0.0 && fraction <= 0.5)) throw UsageError("--girth-inflation: must be within [0, 0.5]");
  return fraction;
}

}  // namespace confluent::app
