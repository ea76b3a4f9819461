#include "tracking/shape_json.h"

#include <array>
#include <cmath>

#include "core/error.h"

namespace confluent::tracking_internal {
namespace {

using Scales = std::array<double, kNumBodySegments>;

nlohmann::json ScalesJson(const Scales& scales) {
  nlohmann::json out = nlohmann::json::object();
  for (int s = 0; s < kNumBodySegments; ++s) out[BodySegmentName(s)] = scales[s];
  return out;
}

// Reads `value[key]` into `scales`, each value in (lo, hi]; an absent key keeps them unless
// `required`.
void ParseScales(const nlohmann::json& value, const std::string& key, bool required, double lo, double hi,
                 const std::string& path, Scales* scales) {
  if (!value.contains(key)) {
    if (required) throw InputError(path, "shape: expected " + key);
    return;
  }
  const nlohmann::json& entry = value[key];
  for (int s = 0; s < kNumBodySegments; ++s) {
    const std::string name = BodySegmentName(s);
    if (!entry.is_object() || !entry.contains(name) || !entry[name].is_number())
      throw InputError(path, "shape: missing " + key + " of segment " + name);
    const double v = entry[name].get<double>();
    if (!(v > lo && v <= hi))
      throw InputError(path, "shape: " + key + " of segment " + name + " is " + entry[name].dump() +
                                 (lo == 0 ? ", not a positive number" : ", not in (-1, 1]"));
    (*scales)[s] = v;
  }
}

}  // namespace

nlohmann::json BodyShapeJson(const BodyShape& shape) {
  return {{"length_scale", ScalesJson(shape.length_scale)}, {"girth_scale", ScalesJson(shape.girth_scale)},
          {"depth_scale", ScalesJson(shape.depth_scale)},   {"taper_scale", ScalesJson(shape.taper_scale)},
          {"depth_offset", ScalesJson(shape.depth_offset)}, {"mid_bulge", ScalesJson(shape.mid_bulge)},
          {"skirt_length_m", shape.skirt_length_m},         {"skirt_flare_m", shape.skirt_flare_m}};
}

BodyShape ParseBodyShapeJson(const nlohmann::json& value, const std::string& path) {
  if (!value.is_object()) throw InputError(path, "shape: expected an object");
  BodyShape shape;
  const double big = 1e6;  // any positive scale
  ParseScales(value, "length_scale", true, 0, big, path, &shape.length_scale);
  ParseScales(value, "girth_scale", true, 0, big, path, &shape.girth_scale);
  ParseScales(value, "depth_scale", false, 0, big, path, &shape.depth_scale);
  ParseScales(value, "taper_scale", false, 0, big, path, &shape.taper_scale);
  ParseScales(value, "depth_offset", false, -1, 1, path, &shape.depth_offset);
  ParseScales(value, "mid_bulge", false, -1, 1, path, &shape.mid_bulge);
  for (const char* key : {"skirt_length_m", "skirt_flare_m"}) {
    if (!value.contains(key)) continue;
    if (!value[key].is_number() || !(value[key].get<double>() >= 0))
      throw InputError(path, std::string("shape: ") + key + " must be a number >= 0");
  }
  shape.skirt_length_m = value.value("skirt_length_m", 0.0);
  shape.skirt_flare_m = value.value("skirt_flare_m", 0.0);
  return shape;
}

}  // namespace confluent::tracking_internal
