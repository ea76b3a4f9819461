#pragma once
// The stages of `confluent run`, in order. Every stage is resumable: it skips the frames whose
// output files exist (all outputs are written atomically), records its per-frame times in the
// TimingLog and reports progress with its own bar.

#include <string>
#include <vector>

#include "pipeline/frame_range.h"
#include "pipeline/camera_selection.h"
#include "pipeline/run_folder.h"
#include "pipeline/run_manifest.h"
#include "calib/capture.h"
#include "core/mesh.h"
#include "core/progress.h"
#include "tracking/body_template.h"
#include "tracking/tracker.h"

namespace confluent {

// What every stage needs to know about the run.
struct RunInputs {
  const Capture* capture = nullptr;
  RunFolder folder;
  FrameRange frames;                 // the frames of this invocation (a shard, or all)
  CameraSelection cameras;           // used and held out (never used, masks only)
  double fps = kAssumedFrameRate;    // of poses.json, motion.bvh and the videos
  std::string masks_dir;             // given masks (<dir>/<cam>/<frame>.png); empty: extract into the run
  std::string scan_path;             // empty: the 3D video uses the template
  const Mesh* scan = nullptr;        // the scan read from scan_path once (null without a scan)
  std::string correspondences_path;  // empty: automatic registration and correspondences
  int threads = 2;
  bool refine_silhouettes = true;    // pull the animated scan onto the used cameras' masks
  int refine_iterations = 18;        // rounds of the silhouette refinement per frame
  // Every this many frames the refinement starts from the deformation; the frames between start
  // from the previous frame's correction, in fewer rounds (pipeline/frame_refinement.h).
  int refine_keyframes = 1;
  bool refine_photo = true;          // then make neighbouring used cameras agree on the texture
  int photo_rounds = 5;              // FrameRefinementOptions::photo_rounds
  int photo_full_resolution_rounds = 2;  // of those, the last ones with the flow at full resolution
  TrackerOptions tracker;            // of the tracking stage
  // BlazePose's landmarks settle limbs the silhouettes leave ambiguous, at the first frame and
  // where a limb seems lost (pipeline/frame_landmarks.h; skipped with a note without Node.js).
  bool landmarks = true;
};

// How much a stage did.
struct StageReport {
  explicit StageReport(std::string name) : stage(std::move(name)) {}
  std::string stage;
  int computed = 0;  // frames computed now
  int skipped = 0;   // frames already finished by an earlier invocation
  double seconds = 0.0;
  std::vector<std::string> notes;  // lines for the summary (warnings, figures)
};

// The mask file of camera `camera` at `frame` used by the run (given masks or the run's own).
std::string RunMaskPath(const RunInputs& inputs, int camera, int frame);

// The masks of one frame for the tracker: held-out cameras left empty. Throws InputError naming
// a missing mask file or one whose size differs from its camera's calibration.
std::vector<Image> TrackingMasks(const RunInputs& inputs, int frame);

// Silhouettes of every camera (held-out ones too, for evaluation) into RUN/masks; skipped when
// masks are given.
StageReport RunSilhouetteStage(const RunInputs& inputs, const ProgressCallback& progress, TimingLog* timings);

// Marker-less tracking of the template: RUN/tracking/<frame>.json (the state that lets a later
// invocation or the next shard continue), RUN/template/<frame>.ply, then RUN/poses.json and
// RUN/motion.bvh over every tracked frame. Returns the fitted shape in `shape`.
StageReport RunTrackingStage(const RunInputs& inputs, const BodyTemplate& body, const ProgressCallback& progress,
                             TimingLog* timings, BodyShape* shape);

// Registration of the template to the scan and the correspondences (given or automatic):
// RUN/correspondences.json and RUN/template_reference.ply (the template in the scan's pose).
StageReport RunCorrespondenceStage(const RunInputs& inputs, const BodyTemplate& body, const BodyShape& shape,
                                   TimingLog* timings);

// Options of the 3D-video render stage.
struct RenderStageOptions {
  std::string view = "orbit";  // renders/<view>/
  int width = 960;
  int height = 720;
};

// Confluent Motion of the scan driven by RUN/template/<frame>.ply: RUN/scan/<frame>.ply (where the
// registration records a first tracked pose, the first frames' templates are eased from the
// registered pose into the tracked ones, pipeline/first_pose_seam.h). With
// `render` (the render stage follows), each refined scan's 3D-video frame is drawn too while
// the frame's images are decoded for the photo refinement, as the render stage would draw it.
StageReport RunDeformStage(const RunInputs& inputs, const BodyTemplate& body, const ProgressCallback& progress,
                           TimingLog* timings, const RenderStageOptions* render = nullptr);

// The 3D video: an orbit around the actor, the scan (or the template without a scan)
// projectively textured from the used cameras, RUN/renders/orbit/<frame>.png and orbit.mp4.
StageReport RunRenderStage(const RunInputs& inputs, const RenderStageOptions& options, const ProgressCallback& progress,
                           TimingLog* timings);

}  // namespace confluent
