// confluent run CAPTURE [--scan S] [--correspondences C] [--exclude-camera NAME]... [--frames A:B]
// --out RUN: capture to 3D video, every stage resumable.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "app/tracking_args.h"
#include "app/commands.h"
#include "app/run_output.h"
#include "core/error.h"
#include "pipeline/run_capture.h"

namespace confluent::app {
namespace fs = std::filesystem;

namespace {

int RunRun(const ParsedArgs& args, const Context& context) {
  RunOptions options;
  options.capture = args.positionals()[0];
  options.out = args.get("out");
  options.frames = args.get("frames");
  options.held_out = args.get_all("exclude-camera");
  options.masks_dir = args.get("masks");
  options.scan = args.get("scan");
  options.no_scan = args.has("no-scan");
  options.allow_open_scan = args.has("allow-open-scan");
  options.correspondences = args.get("correspondences");
  options.refine_silhouettes = !args.has("no-refine");
  options.refine_iterations = args.get_int("refine-iterations", options.refine_iterations);
  if (options.refine_iterations < 1 || options.refine_iterations > 50)
    throw UsageError("--refine-iterations: must be within [1, 50]");
  options.refine_keyframes = args.get_int("refine-keyframes", options.refine_keyframes);
  if (options.refine_keyframes < 1 || options.refine_keyframes > 1000)
    throw UsageError("--refine-keyframes: must be within [1, 1000]");
  options.refine_photo = !args.has("no-photo-refine");
  options.photo_rounds = args.get_int("photo-rounds", options.photo_rounds);
  if (options.photo_rounds < 1 || options.photo_rounds > 20) throw UsageError("--photo-rounds: must be within [1, 20]");
  // Fewer rounds than the default full-resolution ones: all of them at full resolution.
  options.photo_full_resolution_rounds =
      args.get_int("photo-full-res-rounds", std::min(options.photo_full_resolution_rounds, options.photo_rounds));
  if (options.photo_full_resolution_rounds < 0 || options.photo_full_resolution_rounds > options.photo_rounds)
    throw UsageError("--photo-full-res-rounds: must be within [0, --photo-rounds = " + std::to_string(options.photo_rounds) + "]");
  options.landmarks = !args.has("no-landmarks");
  options.girth_inflation = GirthInflationFromArgs(args);
  options.shape_samples = ShapeSamplesFromArgs(args);
  options.fit_downscale = FitDownscaleFromArgs(args);
  options.threads = args.get_int("threads", options.threads);
  if (options.threads < 1 || options.threads > 64) throw UsageError("--threads: must be within [1, 64]");
  options.fps = args.get_double("fps", 0.0);
  if (args.has("fps") && !(options.fps > 0.0 && options.fps <= 1000.0)) throw UsageError("--fps: must be within (0, 1000]");
  options.render = !args.has("no-render");
  options.render_options.width = args.get_int("render-width", options.render_options.width);
  options.render_options.height = args.get_int("render-height", options.render_options.height);
  if (options.render_options.width < 16 || options.render_options.height < 16 || options.render_options.width > 8192 ||
      options.render_options.height > 8192)
    throw UsageError("--render-width/--render-height: must be within [16, 8192]");
  for (const auto& [name, values] : args.values_) options.command_line[name] = values;
  options.version = CONFLUENT_VERSION;

  const std::string timings_path = RunCapture(options, context.make_progress, PrintStageReport, PrintRunLine);
  std::printf("done: %s (timings in %s)\n", options.out.c_str(), timings_path.c_str());
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
      {"refine-keyframes", "N", "refine only every N-th frame from its deformation, the others from the previous frame's correction in fewer rounds (default 1)"},
      {"no-photo-refine", "", "skip the photo-consistency refinement that follows the silhouette refinement"},
      {"photo-rounds", "N", "rounds of the photo-consistency refinement per frame (default 5)"},
      {"photo-full-res-rounds", "N", "of those, the last N measure the flow between cameras at full resolution instead of half: sharper texture on fine patterns (default 2, or all of fewer rounds)"},
      GirthInflationOptionSpec(),
      ShapeSamplesOptionSpec(),
      FitDownscaleOptionSpec(),
      {"no-landmarks", "", "track from the silhouettes alone, without BlazePose's body landmarks (first frame, lost limbs, every 5th frame)"},
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
