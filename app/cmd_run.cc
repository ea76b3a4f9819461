// confluent run CAPTURE [--scan S] [--correspondences C] [--exclude-camera NAME]... [--frames A:B]
// --out RUN: capture to 3D video, every stage resumable.

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "core/error.h"
#include "pipeline/run_manifest.h"
#include "pipeline/run_record.h"
#include "pipeline/run_stages.h"

namespace confluent::app {
namespace fs = std::filesystem;

namespace {

void PrintReport(const StageReport& report) {
  std::printf("%-16s %6d computed %6d already done %9.1f s\n", report.stage.c_str(), report.computed, report.skipped,
              report.seconds);
  const std::size_t shown = std::min<std::size_t>(report.notes.size(), 8);
  for (std::size_t i = 0; i < shown; ++i) std::printf("    %s\n", report.notes[i].c_str());
  if (report.notes.size() > shown) std::printf("    ... %zu more\n", report.notes.size() - shown);
  std::fflush(stdout);
}

int RunRun(const ParsedArgs& args, const Context& context) {
  const std::string root = args.positionals()[0];
  CaptureOptions capture_options;
  capture_options.check_every_image_header = false;
  const Capture capture = Capture::Open(root, capture_options);
  const Rig& rig = capture.rig();

  RunInputs inputs;
  inputs.capture = &capture;
  inputs.folder.root = args.get("out");
  inputs.frames = ParseFrameRange(args.get("frames"), capture.num_frames());
  inputs.cameras = CameraSelection(rig, args.get_all("exclude-camera"));
  inputs.cameras.RequireUsed(2, "--exclude-camera");
  const double fps = args.get_double("fps", 0.0);
  if (args.has("fps") && !(fps > 0.0 && fps <= 1000.0)) throw UsageError("--fps: must be within (0, 1000]");
  inputs.fps = RunFrameRate(capture, fps);
  inputs.masks_dir = args.get("masks");
  if (!inputs.masks_dir.empty() && !fs::is_directory(inputs.masks_dir)) throw InputError(inputs.masks_dir, "masks folder not found");
  inputs.scan_path = args.has("no-scan") ? "" : args.get("scan", capture.scan_path());
  Mesh scan;
  if (!inputs.scan_path.empty()) {
    scan = ReadCheckedScan(inputs.scan_path, args.has("allow-open-scan"));
    inputs.scan = &scan;
  }
  inputs.correspondences_path = args.get("correspondences", capture.correspondences_path());
  if (!inputs.correspondences_path.empty() && !fs::exists(inputs.correspondences_path))
    throw InputError(inputs.correspondences_path, "correspondences file not found");
  inputs.refine_silhouettes = !args.has("no-refine");
  inputs.refine_iterations = args.get_int("refine-iterations", inputs.refine_iterations);
  inputs.refine_photo = inputs.refine_silhouettes && !args.has("no-photo-refine");
  if (inputs.refine_iterations < 1 || inputs.refine_iterations > 50)
    throw UsageError("--refine-iterations: must be within [1, 50]");
  inputs.threads = args.get_int("threads", 2);
  if (inputs.threads < 1 || inputs.threads > 64) throw UsageError("--threads: must be within [1, 64]");
  RenderStageOptions render;
  render.width = args.get_int("render-width", render.width);
  render.height = args.get_int("render-height", render.height);
  if (render.width < 16 || render.height < 16 || render.width > 8192 || render.height > 8192)
    throw UsageError("--render-width/--render-height: must be within [16, 8192]");

  fs::create_directories(inputs.folder.root);
  const int stale_temporaries = RemoveStaleTemporaries(inputs.folder.root);
  nlohmann::json options;
  for (const auto& [name, values] : args.values_) options[name] = values;
  RecordRun(inputs, options, CONFLUENT_VERSION);
  // A shard keeps its own log, so that shards running at the same time do not overwrite each other's rows.
  const std::string timings_path =
      inputs.folder.Path(args.has("frames") ? "timings_frames_" + std::to_string(inputs.frames.first) + "-" +
                                                  std::to_string(inputs.frames.end) + ".csv"
                                            : "timings.csv");
  TimingLog timings(timings_path);
  std::printf("run %s: %d cameras (%zu held out), frames %d:%d, %s\n", inputs.folder.root.c_str(), rig.size(),
              inputs.cameras.held_out_names().size(), inputs.frames.first, inputs.frames.end,
              inputs.scan_path.empty() ? "no scan (template 3D video)" : ("scan " + inputs.scan_path).c_str());
  if (stale_temporaries > 0)
    std::printf("removed %d temporary file(s) left by an interrupted run\n", stale_temporaries);
  std::fflush(stdout);

  const BodyTemplate body;
  PrintReport(RunSilhouetteStage(inputs, context.make_progress(), &timings));
  BodyShape shape;
  PrintReport(RunTrackingStage(inputs, body, context.make_progress(), &timings, &shape));
  if (inputs.scan != nullptr) {
    PrintReport(RunCorrespondenceStage(inputs, body, shape, &timings));
    PrintReport(RunDeformStage(inputs, context.make_progress(), &timings));
  }
  if (!args.has("no-render")) PrintReport(RunRenderStage(inputs, render, context.make_progress(), &timings));
  std::printf("done: %s (timings in %s)\n", inputs.folder.root.c_str(), timings_path.c_str());
  return 0;
}

}  // namespace

CommandSpec MakeRunCommand() {
  CommandSpec spec;
  spec.name = "run";
  spec.summary = "capture to 3D video: silhouettes, tracking, correspondences, deformation, renders (resumable)";
  spec.usage = "CAPTURE [--scan S] [--correspondences C] [--exclude-camera NAME]... [--frames A:B] --out RUN";
  spec.description =
      "Stages, in order: silhouettes (RUN/masks), marker-less tracking (RUN/tracking, RUN/template, poses.json,\n"
      "motion.bvh), registration of the template to the scan and correspondences (RUN/correspondences.json,\n"
      "automatic unless given), Confluent Motion refined against the used cameras' silhouettes and then\n"
      "until neighbouring cameras agree on the texture (RUN/scan/<frame>.ply; --no-refine keeps the plain\n"
      "deformation, --no-photo-refine only the silhouette refinement) and the 3D video: an orbit around the\n"
      "actor, projectively textured from the used cameras (RUN/renders/orbit/<frame>.png, orbit.mp4).\n"
      "Without a scan (none given and none in the capture), the 3D video uses the tracked template.\n"
      "Resumable: every file is written atomically and a re-run skips finished frames. --frames A:B makes\n"
      "independent shards; tracking continues from the state of frame A-1 when a previous shard wrote it.\n"
      "Writes run.json (options, input checksums, version) and timings.csv (seconds per stage and frame).";
  spec.min_positionals = spec.max_positionals = 1;
  spec.options = {
      {"out", "RUN", "output folder", false, true},
      {"scan", "FILE", "the actor's scan (default CAPTURE/scan.ply|obj when present)"},
      {"no-scan", "", "ignore any scan: the 3D video uses the template"},
      {"allow-open-scan", "", "accept a scan with holes (boundary edges)"},
      {"correspondences", "FILE", "template<->scan correspondences (default: automatic)"},
      {"exclude-camera", "NAME", "do not use this camera (held out for evaluation)", true},
      {"frames", "A:B", "frame range, B exclusive (default: all frames)"},
      {"masks", "DIR", "use these masks DIR/<cam>/<frame>.png instead of extracting silhouettes"},
      {"no-refine", "", "keep the deformed scan as Confluent Motion gives it (no silhouette refinement)"},
      {"refine-iterations", "N", "rounds of silhouette refinement per frame (default 18)"},
      {"no-photo-refine", "", "skip the photo-consistency refinement that follows the silhouette refinement"},
      {"no-render", "", "skip the 3D-video render stage"},
      {"render-width", "PX", "width of the orbit video (default 960)"},
      {"render-height", "PX", "height of the orbit video (default 720)"},
      {"threads", "N", "worker threads (default 2)"},
      {"fps", "F", "frame rate of poses.json, motion.bvh and the videos (default: the capture's videos', else 25)"},
  };
  spec.run = RunRun;
  return spec;
}

}  // namespace confluent::app
