#pragma once
// INTERNAL (tracking/*.cc only): the template's BodyShape as JSON, shared by poses.json and the
// template registration of correspondences.json. Every scale is keyed by segment name.

#include <nlohmann/json.hpp>
#include <string>

#include "tracking/body_template.h"

namespace confluent::tracking_internal {

// {"length_scale": {...}, "girth_scale": {...}, "depth_scale": {...}, "taper_scale": {...},
//  "skirt_length_m": x, "skirt_flare_m": y}.
nlohmann::json BodyShapeJson(const BodyShape& shape);

// The inverse. length_scale and girth_scale are required; depth_scale and taper_scale (1) and the
// skirt (0) may be absent, as in files written before they existed. Throws InputError naming
// `path` for a missing or non-positive scale.
BodyShape ParseBodyShapeJson(const nlohmann::json& value, const std::string& path);

}  // namespace confluent::tracking_internal
