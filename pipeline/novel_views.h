#pragma once
// Novel views of a finished run (`confluent render`): its animated scan or template,
// projectively textured from the capture's cameras (never from the ones the run held out unless
// asked), along a camera path, to PNG/EXR sequences and an H.264 MP4.

#include <string>
#include <vector>

#include "calib/capture.h"
#include "core/progress.h"
#include "pipeline/finished_run.h"
#include "pipeline/frame_range.h"
#include "render/projective_texture.h"

namespace confluent {

struct NovelViewOptions {
  std::string geometry = "scan";  // "scan" (RUN/scan/) or "template" (RUN/template/)
  // orbit, cameras:NAME,NAME,..., fixed:NAME, fixed:CALIB_DIR/NAME or bullet:FRAME
  std::string path = "orbit";
  int path_frames = 0;            // cameras on the path; 0: one per frame (bullet time: 60)
  int width = 0, height = 0;      // output size; 0: the cameras' own
  std::string format = "png";     // "png" or "exr" (linear)
  bool write_mp4 = false;         // also OUT/<view>.mp4 (needs ffmpeg)
  double fps = 0.0;               // of the MP4; 0: the run's
  std::vector<std::string> excluded;  // cameras that do not texture (besides the run's held-out ones)
  bool texture_from_held_out = false;  // let the run's held-out cameras texture too
  bool over_plate = false;        // a fixed capture camera's view over its clean plate, colours matched
  double edge_softness_px = 0.5;  // with over_plate: Gaussian sigma of the outline's matting
  ProjectiveTextureOptions texturing;

  void Check() const;  // throws UsageError naming an invalid field and its value
};

struct NovelViewSummary {
  std::string view;                // the name of the path: orbit, path, a camera, bullet_<frame>
  std::string view_dir;            // OUT/<view>
  int written = 0;                 // images written
  int width = 0, height = 0;
  int texturing_cameras = 0;       // of the capture's cameras
  double median_setup_ms = 0.0;    // texture setup per frame
  double median_render_ms = 0.0;   // one novel view
  std::string video_path;          // "" without an MP4
  int video_frames = 0;
  double fps = 0.0;
  std::vector<int> missing;        // frames without geometry, skipped
  std::vector<std::string> warnings;
};

// Renders the views of `run` (made from `capture`) over `frames` into `out_dir`. Throws
// UsageError for a bad path or camera name, InputError naming a missing or inconsistent mesh.
NovelViewSummary RenderNovelViews(const FinishedRun& run, const Capture& capture, const FrameRange& frames,
                                  const std::string& out_dir, const NovelViewOptions& options,
                                  const ProgressCallback& progress);

}  // namespace confluent
