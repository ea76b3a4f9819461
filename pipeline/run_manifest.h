#pragma once
// run.json (docs/ARCHITECTURE.md section 4): what a run was made from and how, so that the run
// can be resumed, rendered, evaluated and viewed from its folder alone. This is the one reader
// and the one writer of the file.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/frame_range.h"

namespace confluent {

class Capture;

// The frame rate of a run whose capture does not state one (an images/ folder) and that was
// not given one: the rate of the built-in studio motions.
inline constexpr double kAssumedFrameRate = 25.0;

// `requested` when positive, else the capture's own rate (its videos), else kAssumedFrameRate.
double RunFrameRate(const Capture& capture, double requested = 0.0);

struct RunManifest {
  std::string version;                      // of the confluent that wrote it
  std::string capture;                      // the capture folder, absolute ("" when unknown)
  std::string scan;                         // the scan, absolute ("" without a scan)
  std::string correspondences = "automatic";  // a file, absolute, or "automatic"
  std::string masks = "extracted";          // a folder of given masks, absolute, or "extracted"
  std::vector<std::string> held_out_cameras;  // alphabetical; never used by the run
  FrameRange frames;                        // the range of the invocation that wrote the file
  double fps = 0.0;                         // 0 in files written before the field existed
  nlohmann::json options = nlohmann::json::object();  // the command line's options as given
  nlohmann::json input_checksums;           // identity of the inputs; a resumed run must match
};

// The run.json of run folder `root`.
std::string RunManifestPath(const std::string& root);

// Reads a run.json. Absent fields keep their defaults (older runs). Throws InputError naming
// the file when it is missing, not JSON, not an object, or a field has the wrong type.
RunManifest ReadRunManifest(const std::string& path);

// Writes `manifest` atomically (format "confluent.run/1"). Throws OutputError.
void WriteRunManifest(const std::string& path, const RunManifest& manifest);

}  // namespace confluent
