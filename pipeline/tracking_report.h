#pragma once
// What `confluent track` reports about the tracked frames of a run folder: the overlap of the
// template with every camera's mask (held-out cameras included), overlays, the 3D joint error
// against ground-truth joints, and a per-frame table.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/progress.h"
#include "pipeline/run_stages.h"

namespace confluent {

struct TrackingReportOptions {
  int overlay_every = 25;        // RUN/overlays/<cam>/<frame>.png every N frames (and the last); 0: none
  std::string gt_joints_path;    // joints.json of `confluent synth`: the joint error; "": none
};

struct TrackingReport {
  std::vector<std::string> frame_lines;  // one line per frame for the terminal
  std::vector<std::string> summary_lines;
  nlohmann::json summary;                // as written to RUN/track_summary.json
};

// Reads the tracked frames of `inputs.frames` back from the run folder (tracking/<frame>.json,
// template/<frame>.ply) and writes RUN/overlap.csv, RUN/tracking_frames.csv, RUN/overlays/ and
// RUN/track_summary.json. Throws InputError naming a missing or malformed file.
TrackingReport ReportTracking(const RunInputs& inputs, const BodyTemplate& body, const TrackingReportOptions& options,
                              const ProgressCallback& progress);

}  // namespace confluent
