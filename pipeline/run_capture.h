#pragma once
// `confluent run` as one call: a capture to 3D video, every stage resumable (run_stages.h).

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/progress.h"
#include "pipeline/run_stages.h"

namespace confluent {

// Everything a run needs.
struct RunOptions {
  std::string capture;                 // the recorded camera folder
  std::string out;                     // the run folder
  std::string frames;                  // "A:B" (B exclusive), "A", or "" for all frames
  std::vector<std::string> held_out;   // cameras never used (evaluated later)
  std::string masks_dir;               // given masks <dir>/<cam>/<frame>.png; "": extract them
  std::string scan;                    // the actor's scan; "": the capture's scan.ply|obj when present
  bool no_scan = false;                // ignore any scan: the 3D video uses the template
  bool allow_open_scan = false;        // accept a scan with holes
  std::string correspondences;         // "": the capture's correspondences.json, else automatic
  bool refine_silhouettes = true;
  int refine_iterations = 18;
  int refine_keyframes = 1;            // RunInputs::refine_keyframes
  bool refine_photo = true;
  int photo_rounds = 5;                // RunInputs::photo_rounds
  int photo_full_resolution_rounds = 2;  // RunInputs::photo_full_resolution_rounds
  bool landmarks = true;               // RunInputs::landmarks
  std::optional<double> girth_inflation;  // TrackerOptions::InflateGirthsAlways; absent: the tracker's automatic default
  std::optional<int> shape_samples;       // TrackerOptions::shape_samples; absent: the tracker's default
  std::optional<int> fit_downscale;       // SilhouetteFitOptions::downscale; absent: the tracker's default
  bool render = true;                  // the orbit 3D video
  RenderStageOptions render_options;
  int threads = 2;
  double fps = 0.0;                    // 0: the capture's videos', else kAssumedFrameRate
  nlohmann::json command_line = nlohmann::json::object();  // recorded in run.json as "options"
  std::string version;                 // of the program, recorded in run.json

  void Check() const;  // throws UsageError naming an invalid field and its value
};

// Runs every stage in order. `make_progress` makes one progress callback per stage (may be
// null); `report` receives each stage's report as it finishes and the run's opening lines (may
// be null). Returns the path of the timing log. Throws UsageError, InputError naming the file,
// OutputError; finished frames are kept.
std::string RunCapture(const RunOptions& options, const std::function<ProgressCallback()>& make_progress,
                       const std::function<void(const StageReport&)>& report,
                       const std::function<void(const std::string&)>& say);

}  // namespace confluent
