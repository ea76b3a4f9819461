#pragma once
// Held-out evaluation of a finished run (`confluent evaluate`): the run's animated scan and its
// template, projectively textured from the cameras the run used, rendered into cameras it never
// saw and compared with their images (silhouette IoU and XOR, PSNR/SSIM in the union of the
// silhouettes, the error split, vertex error against ground-truth meshes).

#include <string>
#include <vector>

#include "calib/capture.h"
#include "core/progress.h"
#include "pipeline/evaluation_report.h"
#include "pipeline/finished_run.h"
#include "pipeline/frame_range.h"
#include "render/projective_texture.h"

namespace confluent {

struct EvaluationOptions {
  std::vector<std::string> held_out;  // cameras to score; empty: the ones the run held out
  std::string masks_dir;              // true silhouettes <dir>/<cam>/<frame>.png; "": the run's masks
  std::string gt_meshes_dir;          // meshes with the scan's topology, <dir>/<frame>.ply; "": none
  bool over_plates = true;            // views over each held-out camera's clean plate, else black
  bool match_colour = true;           // with the plates: input colours matched to the held-out camera
  double edge_softness_px = 0.5;      // Gaussian sigma of the outline's matting over the plate
  int every = 1;                      // score every N-th frame
  int side_by_side_every = 10;        // side-by-side pictures every N scored frames (0: none)
  ProjectiveTextureOptions texturing;
  // How the scan is textured: kProjective renders the projective texture directly (the default);
  // kAtlas bakes it into a UV atlas per frame, through an H.264 round trip, and renders the
  // atlas-textured scan (pipeline/evaluation_atlas.h; the template stays projective).
  enum class Texture { kProjective, kAtlas };
  Texture texture = Texture::kProjective;
  int atlas_size_px = 2048;  // kAtlas: the atlas's width and height
  int atlas_supersampling = 4;  // kAtlas: colour samples per pixel and axis (AtlasTexturingOptions)

  void Check() const;  // throws UsageError naming an invalid field and its value
};

// One line for reports, e.g. "best 3 cameras, feather 8 px, no colour balance".
std::string DescribeTextureOptions(const ProjectiveTextureOptions& options);

// Scores `run` (made from `capture`) over `frames`. Writes RUN/metrics.json, metrics.csv,
// plots/*.png, evaluation/<cam>/<frame>.png and report.html, and returns the summary with its
// warnings. Throws UsageError for unknown or missing held-out cameras, InputError naming a
// missing mask or ground-truth mesh, or a run without tracked frames.
EvaluationSummary EvaluateRun(const FinishedRun& run, const Capture& capture, const FrameRange& frames,
                              const EvaluationOptions& options, const ProgressCallback& progress);

}  // namespace confluent
