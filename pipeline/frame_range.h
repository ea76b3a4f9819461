#pragma once
// The --frames A:B option shared by the commands that work on a range of frames.

#include <string>

namespace confluent {

// A half-open range of frame numbers [first, end).
struct FrameRange {
  int first = 0;
  int end = 0;
  int size() const { return end - first; }
  bool contains(int frame) const { return frame >= first && frame < end; }
};

// Parses "A:B" (B exclusive; either side may be empty) or "A" (one frame) against a capture of
// `num_frames` frames; "" means all frames. Throws UsageError naming --frames for bad text or a
// range that is empty or outside 0:num_frames.
FrameRange ParseFrameRange(const std::string& text, int num_frames);

// "000042": the six-digit stem of a frame's files.
std::string FrameStem(int frame);

}  // namespace confluent
