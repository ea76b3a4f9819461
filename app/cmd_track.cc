// confluent track CAPTURE [--exclude-camera NAME]... [--masks DIR] --out RUN: marker-less motion
// capture with the 16-segment body template. The arguments of the run's tracking stage
// (pipeline/run_stages.h, resumable) and of its report (pipeline/tracking_report.h).

#include <cstdio>
#include <filesystem>

#include "app/tracking_args.h"
#include "app/commands.h"
#include "calib/capture.h"
#include "core/error.h"
#include "pipeline/run_stages.h"
#include "pipeline/tracking_report.h"

namespace confluent::app {
namespace fs = std::filesystem;

namespace {

int RunTrack(const ParsedArgs& args, const Context& context) {
  const std::string root = args.positionals()[0];
  CaptureOptions capture_options;
  capture_options.check_every_image_header = false;
  const Capture capture = Capture::Open(root, capture_options);
  RunInputs inputs;
  inputs.capture = &capture;
  inputs.folder.root = args.get("out");
  inputs.cameras = CameraSelection(capture.rig(), args.get_all("exclude-camera"));
  inputs.cameras.RequireUsed(2, "--exclude-camera");
  inputs.masks_dir = args.get("masks", (fs::path(root) / "masks").string());
  if (!fs::is_directory(inputs.masks_dir))
    throw InputError(inputs.masks_dir, "no masks folder (run `confluent silhouettes` first, or pass --masks DIR)");
  inputs.frames = ParseFrameRange(args.get("frames"), capture.num_frames());
  inputs.fps = RunFrameRate(capture);
  if (const std::optional<int> factor = FitDownscaleFromArgs(args)) inputs.tracker.fit.downscale = *factor;
  inputs.tracker.fit.num_threads = args.get_int("threads", inputs.tracker.fit.num_threads);
  if (const std::optional<double> inflation = GirthInflationFromArgs(args)) inputs.tracker.InflateGirthsAlways(*inflation);
  if (const std::optional<int> samples = ShapeSamplesFromArgs(args)) inputs.tracker.shape_samples = *samples;
  inputs.tracker.Check();
  inputs.landmarks = !args.has("no-landmarks");
  TrackingReportOptions report_options;
  report_options.overlay_every = args.get_int("overlay-every", report_options.overlay_every);
  report_options.gt_joints_path = args.get("gt-joints");

  fs::create_directories(inputs.folder.root);
  TimingLog timings(inputs.folder.Path("timings.csv"));
  const BodyTemplate body;
  BodyShape shape;
  const StageReport tracked = RunTrackingStage(inputs, body, context.make_progress(), &timings, &shape);
  const TrackingReport report = ReportTracking(inputs, body, report_options, context.make_progress());
  for (const std::string& line : report.frame_lines) std::printf("%s\n", line.c_str());
  for (const std::string& line : report.summary_lines) std::printf("%s\n", line.c_str());
  for (const std::string& note : tracked.notes)
    if (note.find("landmarks") != std::string::npos) std::printf("%s\n", note.c_str());
  std::printf("poses in %s, motion in %s, meshes in %s\n", inputs.folder.Path("poses.json").c_str(),
              inputs.folder.Path("motion.bvh").c_str(), inputs.folder.Path("template").c_str());
  return 0;
}

}  // namespace

CommandSpec MakeTrackCommand() {
  CommandSpec spec;
  spec.name = "track";
  spec.summary = "marker-less motion capture: fit the 16-segment body template to the silhouettes";
  spec.usage = "CAPTURE [--exclude-camera NAME]... [--masks DIR] --out RUN";
  spec.description =
      "Initialises the body template automatically on the first frame (placement from the visual hull, then a\n"
      "joint shape-and-pose fit) and tracks it frame by frame with Ceres (silhouette distance transforms,\n"
      "contour rays, constant-velocity prediction, bad-frame recovery, lost limbs searched again and, where\n"
      "Node.js and BlazePose are installed, turned towards the body landmarks that the cameras agree on). Reads\n"
      "CAPTURE/masks/<cam>/<frame>.png (or --masks DIR). Excluded (held-out) cameras are not used; when their\n"
      "masks exist, their overlap is reported. Writes RUN/poses.json, RUN/motion.bvh (Y-up, cm),\n"
      "RUN/template/<frame>.ply (face label = segment), RUN/tracking/<frame>.json (the state a re-run resumes\n"
      "from: finished frames are kept), RUN/overlap.csv (IoU per frame and camera),\n"
      "RUN/overlays/<cam>/<frame>.png (template contour red, mask green), RUN/tracking_frames.csv (seconds, CPU\n"
      "seconds and iterations per frame), RUN/timings.csv and RUN/track_summary.json, and prints a per-frame\n"
      "summary.";
  spec.min_positionals = spec.max_positionals = 1;
  spec.options = {
      {"out", "RUN", "output folder", false, true},
      {"exclude-camera", "NAME", "do not use this camera (held out)", true},
      {"masks", "DIR", "masks folder DIR/<cam>/<frame>.png (default CAPTURE/masks)"},
      {"frames", "A:B", "frame range, B exclusive (default: all frames)"},
      {"gt-joints", "FILE", "ground-truth joints.json of `confluent synth`: report the 3D joint error"},
      {"overlay-every", "N", "write overlays every N frames (default 25; 0 = none)"},
      FitDownscaleOptionSpec(),
      {"threads", "N", "solver threads (default 2)"},
      GirthInflationOptionSpec(),
      ShapeSamplesOptionSpec(),
      {"no-landmarks", "", "do not ask BlazePose's landmarks where a limb is ambiguous (first frame, lost limbs, every 5th frame)"},
  };
  spec.run = RunTrack;
  return spec;
}

}  // namespace confluent::app
