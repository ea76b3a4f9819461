#pragma once
// Small statistics over plain vectors.

#include <vector>

namespace confluent {

// The median of `values` (the upper middle one for an even count); 0 when empty.
double Median(std::vector<double> values);

}  // namespace confluent
