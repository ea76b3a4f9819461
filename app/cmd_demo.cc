// confluent demo: the README's main job on the embedded default capture.

#include <cstdio>
#include <filesystem>

#include "app/commands.h"
#include "app/run_output.h"
#include "pipeline/evaluation.h"
#include "pipeline/finished_run.h"
#include "pipeline/run_capture.h"
#include "pipeline/run_folder.h"
#include "calib/capture.h"
#include "calib/rig_check.h"
#include "core/error.h"
#include "core/image_io.h"
#include "studio/presets.h"

namespace confluent::app {
namespace fs = std::filesystem;
namespace {

int RunDemo(const ParsedArgs& args, const Context& context) {
  const fs::path out = args.get("out", "demo");
  const std::string preset = args.get("preset", "default");
  const fs::path capture_dir = out / "capture";
  const fs::path truth_dir = out / "capture_gt";

  double synth_seconds = 0;
  // 1. The embedded default capture, synthesised once (a finished capture has its synth.json).
  if (!fs::exists(truth_dir / "synth.json")) {
    std::printf("[1/4] synthesising the default capture (%s preset) into %s\n", preset.c_str(), capture_dir.c_str());
    StudioSynthOptions options = StudioSynthPreset(preset, "--preset");
    options.capture_dir = capture_dir.string();
    options.ground_truth_dir = truth_dir.string();
    const StudioSynthSummary summary = SynthesizeCapture(options, context.make_progress());
    synth_seconds = summary.seconds;
    std::printf("      %d cameras x %d frames, actor %d triangles, %.1f s\n", summary.num_cameras, summary.num_frames,
                summary.num_triangles, summary.seconds);
  } else {
    std::printf("[1/4] reusing the capture in %s\n", capture_dir.c_str());
  }

  // 2. Validate the recorded camera folder and check its calibration (overlays).
  const Capture capture = Capture::Open(capture_dir.string());
  const RigCheckReport report = CheckRig(capture.rig());
  const fs::path check_dir = out / "check";
  for (int c = 0; c < capture.num_cameras(); ++c)
    WriteImage((check_dir / (capture.rig().cameras[c].name + ".png")).string(),
               DrawWorldOverlay(capture.rig().cameras[c], capture.ReadFrame(c, 0)));
  std::printf("[2/4] capture valid: %d cameras, %d frames; calibration: %zu warning(s), overlays in %s\n",
              capture.num_cameras(), capture.num_frames(), report.warnings.size(), check_dir.c_str());
  for (const std::string& warning : report.warnings) std::printf("      warning: %s\n", warning.c_str());

  // 3. The pipeline with the studio's held-out cameras excluded (resumes when run again).
  std::vector<std::string> heldout;
  for (const std::string& name : capture.rig().names())
    if (name.rfind("holdout", 0) == 0) heldout.push_back(name);
  if (heldout.empty()) throw InputError(capture_dir.string(), "the capture has no holdout<N> cameras to evaluate on");
  const fs::path run_dir = out / "run";
  RunOptions run;
  run.capture = capture_dir.string();
  run.out = run_dir.string();
  run.held_out = heldout;
  run.version = CONFLUENT_VERSION;
  run.command_line = {{"out", {run.out}}, {"exclude-camera", heldout}};
  std::string held_out_args;
  for (const std::string& name : heldout) held_out_args += " --exclude-camera " + name;
  std::printf("[3/4] confluent run %s --out %s%s\n", run.capture.c_str(), run.out.c_str(), held_out_args.c_str());
  std::fflush(stdout);
  RunCapture(run, context.make_progress, PrintStageReport, PrintRunLine);

  // 4. Held-out evaluation against the ground truth.
  // Every 4th frame keeps the demo short (on the default capture, scoring every 5th frame gave the
  // same mean IoU as every frame, to 0.001); `confluent evaluate` without --every scores them all.
  EvaluationOptions evaluation;
  evaluation.held_out = heldout;
  evaluation.masks_dir = (truth_dir / "masks").string();
  evaluation.gt_meshes_dir = (truth_dir / "meshes").string();
  evaluation.every = args.get_int("evaluate-every", 4);
  if (evaluation.every < 1) throw UsageError("--evaluate-every: must be >= 1");
  std::printf("[4/4] confluent evaluate --run %s --masks %s --gt-meshes %s --every %d\n", run.out.c_str(),
              evaluation.masks_dir.c_str(), evaluation.gt_meshes_dir.c_str(), evaluation.every);
  std::fflush(stdout);
  const FinishedRun finished = OpenFinishedRun(run.out, "");
  const EvaluationSummary summary = EvaluateRun(finished, capture, FrameRange{0, capture.num_frames()}, evaluation,
                                                context.make_progress ? context.make_progress() : ProgressCallback());
  PrintEvaluation(summary, finished.folder);

  TimingLog timings((run_dir / "timings.csv").string());
  std::printf("\ntime per stage (s): synth %.0f (when made), silhouettes %.1f, tracking %.1f, correspondences %.1f, "
              "deform %.1f, silhouette refinement %.1f, photo refinement %.1f, render %.1f\n", synth_seconds, timings.StageSeconds("silhouettes"),
              timings.StageSeconds("tracking"), timings.StageSeconds("correspondences"),
              timings.StageSeconds("deform_factor") + timings.StageSeconds("deform") + timings.StageSeconds("deform_write"),
              timings.StageSeconds("refine_factor") + timings.StageSeconds("refine_read") + timings.StageSeconds("refine"),
              timings.StageSeconds("photo_refine_read") + timings.StageSeconds("photo_refine"),
              timings.StageSeconds("render_read") + timings.StageSeconds("render") + timings.StageSeconds("render_write") +
                  timings.StageSeconds("video"));
  std::printf("3D video: %s\nreport:   %s\n", (run_dir / "renders" / "orbit.mp4").c_str(), (run_dir / "report.html").c_str());
  return 0;
}

}  // namespace

CommandSpec MakeDemoCommand() {
  CommandSpec spec;
  spec.name = "demo";
  spec.summary = "synthesise the embedded default capture and run the pipeline on it";
  spec.usage = "[--out DIR] [--preset default|tiny]";
  spec.description =
      "Synthesises the default studio capture into DIR/capture and its ground truth into DIR/capture_gt (once;\n"
      "reused afterwards), checks the calibration (overlays in DIR/check), runs `confluent run` with the\n"
      "studio's held-out cameras excluded (DIR/run; resumes when interrupted) and `confluent evaluate` on them\n"
      "against the ground truth, then prints the summary table and where the 3D video and report.html are.";
  spec.options = {
      {"out", "DIR", "output folder (default ./demo)"},
      {"preset", "NAME", "studio preset: default or tiny (default: default)"},
      {"evaluate-every", "N", "score every N-th frame on the held-out cameras (default 4)"},
  };
  spec.run = RunDemo;
  return spec;
}

}  // namespace confluent::app
