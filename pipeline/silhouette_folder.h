#pragma once
// `confluent silhouettes`: every camera's masks extracted into a folder, with contact sheets of
// the masks over the images, a summary.json, and optionally the IoU against reference masks.

#include <string>
#include <vector>

#include "calib/capture.h"
#include "core/progress.h"
#include "pipeline/frame_range.h"
#include "silhouette/silhouette.h"

namespace confluent {

struct SilhouetteFolderOptions {
  SilhouetteOptions silhouettes;
  bool overlays = true;      // OUT/overlays/<frame>.png: every camera's image with its mask, tiled
  int overlay_width = 480;   // of each camera's tile
  std::string compare_dir;   // reference masks <dir>/<cam>/<frame>.png: IoU per camera; "": none
};

struct SilhouetteFolderSummary {
  SilhouetteSummary extraction;
  std::vector<std::string> lines;  // the per-camera table (and the IoU line) for the terminal
  std::string overlay_dir;         // "" without contact sheets
  std::string summary_path;        // OUT/summary.json
};

// Writes OUT/<cam>/<frame>.png for `frames`, the contact sheets and OUT/summary.json. Throws
// InputError naming a frame or a reference mask of another size, OutputError when writing fails.
SilhouetteFolderSummary ExtractSilhouettesToFolder(const Capture& capture, const FrameRange& frames,
                                                   const std::string& out_dir, const SilhouetteFolderOptions& options,
                                                   const ProgressCallback& progress);

}  // namespace confluent
