#pragma once
// The tracker options that `confluent run` and `confluent track` share.

#include "app/command_line.h"

namespace confluent::app {

// --girth-inflation F.
OptionSpec GirthInflationOptionSpec();

// TrackerOptions::girth_inflation_max from --girth-inflation (0 when absent). Throws UsageError
// outside [0, 0.5].
double GirthInflationFromArgs(const ParsedArgs& args);

}  // namespace confluent::app
