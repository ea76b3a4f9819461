#include "pipeline/frame_range.h"

#include <cstdio>

#include "core/error.h"

namespace confluent {

FrameRange ParseFrameRange(const std::string& text, int num_frames) {
  FrameRange range{0, num_frames};
  if (text.empty()) return range;
  auto number = [&](const std::string& part, int fallback) {
    if (part.empty()) return fallback;
    std::size_t used = 0;
    int value = 0;
    try {
      value = std::stoi(part, &used);
    } catch (const std::exception&) {
      used = std::string::npos;
    }
    if (used != part.size()) throw UsageError("--frames: expected A:B with frame numbers, got '" + text + "'");
    return value;
  };
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos) {
    range.first = number(text, 0);
    range.end = range.first + 1;
  } else {
    range.first = number(text.substr(0, colon), 0);
    range.end = number(text.substr(colon + 1), num_frames);
  }
  if (range.first < 0 || range.end > num_frames || range.first >= range.end)
    throw UsageError("--frames " + text + ": not a non-empty range within 0:" + std::to_string(num_frames));
  return range;
}

std::string FrameStem(int frame) {
  char name[16];
  std::snprintf(name, sizeof name, "%06d", frame);
  return name;
}

}  // namespace confluent
