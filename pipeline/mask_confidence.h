#pragma once
// The run's record of how far its silhouettes can be trusted: RUN/mask_confidence.json, written by
// the silhouette stage (the masks on disk, checked against each other on a sample of frames) and
// shown by the run's log and report.html.

#include <string>
#include <vector>

#include "calib/camera.h"
#include "silhouette/multiview.h"

namespace confluent {

// RUN/mask_confidence.json, read back.
struct MaskConfidenceRecord {
  std::string source;      // which frames were checked: "sample" (evenly spaced over the run's)
  double min_confidence = 0.8;
  double mean_confidence = 1;
  int camera_frames = 0;   // checked
  std::vector<std::string> camera_names;   // rig order
  std::vector<double> camera_confidence;   // mean per camera (1 for cameras not checked)
  std::vector<int> camera_checked;         // camera-frames checked per camera (0: held out, or no mask)
  std::vector<std::string> low_camera_names;  // per camera-frame below min_confidence ...
  std::vector<int> low_frames;                // ... its frame ...
  std::vector<double> low_confidence;         // ... and its confidence
  std::string warning;     // "" when the masks can be trusted
};

// The record of `trust` (from SummarizeMaskTrust / AssessMaskTrust) for `rig`.
MaskConfidenceRecord MakeMaskConfidenceRecord(const Rig& rig, const MaskTrust& trust, double min_confidence,
                                              const std::string& source);

// Writes `record` to `path` atomically. Throws OutputError.
void WriteMaskConfidence(const std::string& path, const MaskConfidenceRecord& record);

// Reads a file WriteMaskConfidence wrote. Throws InputError naming the file when it is malformed.
MaskConfidenceRecord ReadMaskConfidence(const std::string& path);

// The low-confidence camera-frames in one line, frames as ranges per camera, worst camera first:
// "cam02 frames 0-9; cam01 frames 3, 5-6". At most `max_cameras` cameras are named ("and N more
// cameras"). "" when none.
std::string LowConfidenceList(const MaskConfidenceRecord& record, int max_cameras = 4);

}  // namespace confluent
