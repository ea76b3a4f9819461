// confluent demo: the README's main job on the embedded default capture.

#include <cstdio>
#include <filesystem>

#include "app/commands.h"
#include "calib/capture.h"
#include "calib/rig_check.h"
#include "core/error.h"
#include "core/image_io.h"
#include "render/studio_presets.h"

namespace confluent::app {
namespace fs = std::filesystem;
namespace {

int RunDemo(const ParsedArgs& args, const Context& context) {
  const fs::path out = args.get("out", "demo");
  const std::string preset = args.get("preset", "default");
  const fs::path capture_dir = out / "capture";
  const fs::path truth_dir = out / "capture_gt";

  // 1. The embedded default capture, synthesised once (a finished capture has its synth.json).
  if (!fs::exists(truth_dir / "synth.json")) {
    std::printf("[1/3] synthesising the default capture (%s preset) into %s\n", preset.c_str(), capture_dir.c_str());
    StudioSynthOptions options = StudioSynthPreset(preset, "--preset");
    options.capture_dir = capture_dir.string();
    options.ground_truth_dir = truth_dir.string();
    const StudioSynthSummary summary = SynthesizeCapture(options, context.make_progress());
    std::printf("      %d cameras x %d frames, actor %d triangles, %.1f s\n", summary.num_cameras, summary.num_frames,
                summary.num_triangles, summary.seconds);
  } else {
    std::printf("[1/3] reusing the capture in %s\n", capture_dir.c_str());
  }

  // 2. Validate the recorded camera folder.
  const Capture capture = Capture::Open(capture_dir.string());
  std::printf("[2/3] capture valid: %d cameras, %d frames\n", capture.num_cameras(), capture.num_frames());

  // 3. Calibration check with overlays, and hull consistency against the ground-truth masks.
  const RigCheckReport report = CheckRig(capture.rig());
  const fs::path check_dir = out / "check";
  std::vector<Image> masks;
  for (int c = 0; c < capture.num_cameras(); ++c) {
    WriteImage((check_dir / (capture.rig().cameras[c].name + ".png")).string(),
               DrawWorldOverlay(capture.rig().cameras[c], capture.ReadFrame(c, 0)));
    masks.push_back(ReadMaskFile((truth_dir / "masks" / capture.rig().cameras[c].name / "000000.png").string()));
  }
  const std::vector<double> ious = VisualHullConsistency(capture.rig(), masks, {});
  double mean_iou = 0;
  for (double iou : ious) mean_iou += iou / ious.size();
  std::printf("[3/3] calibration: %zu warning(s); visual-hull consistency of the true masks: mean IoU %.3f\n",
              report.warnings.size(), mean_iou);
  std::printf("\n%s\noverlays: %s\n", report.ToString().c_str(), check_dir.c_str());
  return 0;
}

}  // namespace

CommandSpec MakeDemoCommand() {
  CommandSpec spec;
  spec.name = "demo";
  spec.summary = "synthesise the embedded default capture and run the pipeline on it";
  spec.usage = "[--out DIR] [--preset default|tiny]";
  spec.description =
      "Synthesises the default studio capture into DIR/capture (once; reused afterwards), validates it, and\n"
      "checks its calibration (overlays in DIR/check). The later pipeline stages join as they land.";
  spec.options = {
      {"out", "DIR", "output folder (default ./demo)"},
      {"preset", "NAME", "studio preset: default or tiny (default: default)"},
  };
  spec.run = RunDemo;
  return spec;
}

}  // namespace confluent::app
