#include "pipeline/run_capture.h"

#include <filesystem>

#include "core/error.h"
#include "pipeline/run_record.h"

namespace confluent {
namespace fs = std::filesystem;

void RunOptions::Check() const {
  if (capture.empty()) throw UsageError("RunOptions.capture: empty (name the capture folder)");
  if (out.empty()) throw UsageError("RunOptions.out: empty (name the run folder)");
  RequireOption(refine_iterations >= 1 && refine_iterations <= 50, "RunOptions.refine_iterations", refine_iterations,
                "within [1, 50]");
  RequireOption(refine_keyframes >= 1 && refine_keyframes <= 1000, "RunOptions.refine_keyframes", refine_keyframes,
                "within [1, 1000]");
  RequireOption(photo_rounds >= 1 && photo_rounds <= 20, "RunOptions.photo_rounds", photo_rounds, "within [1, 20]");
  RequireOption(photo_full_resolution_rounds >= 0 && photo_full_resolution_rounds <= photo_rounds,
                "RunOptions.photo_full_resolution_rounds", photo_full_resolution_rounds,
                "within [0, photo_rounds = " + std::to_string(photo_rounds) + "]");
  RequireOption(threads >= 1 && threads <= 64, "RunOptions.threads", threads, "within [1, 64]");
  RequireOption(fps >= 0.0 && fps <= 1000.0, "RunOptions.fps", fps, "within [0, 1000] (0: automatic)");
  RequireOption(render_options.width >= 16 && render_options.width <= 8192, "RunOptions.render_options.width",
                render_options.width, "within [16, 8192]");
  RequireOption(render_options.height >= 16 && render_options.height <= 8192, "RunOptions.render_options.height",
                render_options.height, "within [16, 8192]");
}

std::string RunCapture(const RunOptions& options, const std::function<ProgressCallback()>& make_progress,
                       const std::function<void(const StageReport&)>& report,
                       const std::function<void(const std::string&)>& say) {
  options.Check();
  const auto progress = [&] { return make_progress ? make_progress() : ProgressCallback(); };
  const auto tell = [&](const std::string& line) {
    if (say) say(line);
  };
  const auto done = [&](const StageReport& stage) {
    if (report) report(stage);
  };
  CaptureOptions capture_options;
  capture_options.check_every_image_header = false;
  const Capture capture = Capture::Open(options.capture, capture_options);
  const Rig& rig = capture.rig();

  RunInputs inputs;
  inputs.capture = &capture;
  inputs.folder.root = options.out;
  inputs.frames = ParseFrameRange(options.frames, capture.num_frames());
  inputs.cameras = CameraSelection(rig, options.held_out);
  inputs.cameras.RequireUsed(2, "--exclude-camera");
  inputs.fps = RunFrameRate(capture, options.fps);
  inputs.masks_dir = options.masks_dir;
  if (!inputs.masks_dir.empty() && !fs::is_directory(inputs.masks_dir))
    throw InputError(inputs.masks_dir, "masks folder not found");
  inputs.scan_path = options.no_scan ? "" : options.scan.empty() ? capture.scan_path() : options.scan;
  Mesh scan;
  if (!inputs.scan_path.empty()) {
    scan = ReadCheckedScan(inputs.scan_path, options.allow_open_scan);
    inputs.scan = &scan;
  }
  inputs.correspondences_path = options.correspondences.empty() ? capture.correspondences_path() : options.correspondences;
  if (!inputs.correspondences_path.empty() && !fs::exists(inputs.correspondences_path))
    throw InputError(inputs.correspondences_path, "correspondences file not found");
  inputs.refine_silhouettes = options.refine_silhouettes;
  inputs.refine_iterations = options.refine_iterations;
  inputs.refine_keyframes = options.refine_keyframes;
  inputs.refine_photo = options.refine_silhouettes && options.refine_photo;
  inputs.photo_rounds = options.photo_rounds;
  inputs.photo_full_resolution_rounds = options.photo_full_resolution_rounds;
  inputs.threads = options.threads;
  inputs.landmarks = options.landmarks;
  if (options.girth_inflation) inputs.tracker.InflateGirthsAlways(*options.girth_inflation);
  if (options.shape_samples) inputs.tracker.shape_samples = *options.shape_samples;
  if (options.fit_downscale) inputs.tracker.fit.downscale = *options.fit_downscale;
  inputs.tracker.Check();

  fs::create_directories(inputs.folder.root);
  const int stale_temporaries = RemoveStaleTemporaries(inputs.folder.root);
  RecordRun(inputs, options.command_line, options.version);
  // A shard keeps its own log, so that shards running at the same time do not overwrite each other's rows.
  const std::string timings_path =
      inputs.folder.Path(!options.frames.empty() ? "timings_frames_" + std::to_string(inputs.frames.first) + "-" +
                                                       std::to_string(inputs.frames.end) + ".csv"
                                                 : "timings.csv");
  TimingLog timings(timings_path);
  tell("run " + inputs.folder.root + ": " + std::to_string(rig.size()) + " cameras (" +
       std::to_string(inputs.cameras.held_out_names().size()) + " held out), frames " +
       std::to_string(inputs.frames.first) + ":" + std::to_string(inputs.frames.end) + ", " +
       (inputs.scan_path.empty() ? std::string("no scan (template 3D video)") : "scan " + inputs.scan_path));
  if (stale_temporaries > 0)
    tell("removed " + std::to_string(stale_temporaries) + " temporary file(s) left by an interrupted run");

  const BodyTemplate body;
  done(RunSilhouetteStage(inputs, progress(), &timings));
  BodyShape shape;
  done(RunTrackingStage(inputs, body, progress(), &timings, &shape));
  if (inputs.scan != nullptr) {
    done(RunCorrespondenceStage(inputs, body, shape, &timings));
    done(RunDeformStage(inputs, body, progress(), &timings, options.render ? &options.render_options : nullptr));
  }
  if (options.render) done(RunRenderStage(inputs, options.render_options, progress(), &timings));
  return timings_path;
}

}  // namespace confluent
