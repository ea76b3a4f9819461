// confluent evaluate [CAPTURE] --run RUN [--heldout NAME]...: the arguments of the held-out
// evaluation (pipeline/evaluation.h) and its summary on the terminal.

#include <cstdio>

#include "app/commands.h"
#include "app/run_output.h"
#include "app/texture_args.h"
#include "core/error.h"
#include "pipeline/evaluation.h"
#include "pipeline/finished_run.h"

namespace confluent::app {

namespace {

int RunEvaluate(const ParsedArgs& args, const Context& context) {
  const FinishedRun finished = OpenFinishedRun(args.get("run"), args.positionals().empty() ? "" : args.positionals()[0]);
  CaptureOptions capture_options;
  capture_options.check_every_image_header = false;
  const Capture capture = Capture::Open(finished.capture_root, capture_options);
  const FrameRange range = ParseFrameRange(args.get("frames"), capture.num_frames());
  EvaluationOptions options;
  options.held_out = args.get_all("heldout");
  options.masks_dir = args.get("masks");
  options.gt_meshes_dir = args.get("gt-meshes");
  const std::string background = args.get("background", "plate");
  if (background != "plate" && background != "black")
    throw UsageError("--background: expected plate or black, got '" + background + "'");
  options.over_plates = background == "plate";
  options.match_colour = !args.has("no-colour-match");
  options.edge_softness_px = args.get_double("edge-softness", options.edge_softness_px);
  if (!(options.edge_softness_px >= 0.0 && options.edge_softness_px <= 5.0))
    throw UsageError("--edge-softness: must be within [0, 5] pixels");
  options.every = args.get_int("every", options.every);
  if (options.every < 1) throw UsageError("--every: must be >= 1");
  options.side_by_side_every = args.get_int("side-by-side-every", options.side_by_side_every);
  if (options.side_by_side_every < 0) throw UsageError("--side-by-side-every: must be >= 0");
  options.texturing = TextureOptionsFromArgs(args);
  const std::string texture = args.get("texture", "projective");
  if (texture != "projective" && texture != "atlas")
    throw UsageError("--texture: expected projective or atlas, got '" + texture + "'");
  options.texture = texture == "atlas" ? EvaluationOptions::Texture::kAtlas : EvaluationOptions::Texture::kProjective;
  options.atlas_size_px = args.get_int("atlas-size", options.atlas_size_px);
  if (options.atlas_size_px < 64 || options.atlas_size_px > 16384)
    throw UsageError("--atlas-size: must be within [64, 16384] texels");
  options.atlas_supersampling = args.get_int("atlas-samples", options.atlas_supersampling);
  if (options.atlas_supersampling < 1 || options.atlas_supersampling > 4)
    throw UsageError("--atlas-samples: must be within [1, 4]");

  const EvaluationSummary summary = EvaluateRun(finished, capture, range, options, context.make_progress());
  PrintEvaluation(summary, finished.folder);
  return 0;
}

}  // namespace

CommandSpec MakeEvaluateCommand() {
  CommandSpec spec;
  spec.name = "evaluate";
  spec.summary = "score a run on held-out cameras: silhouette IoU/XOR, PSNR/SSIM, vertex error, report.html";
  spec.usage = "[CAPTURE] --run RUN [--heldout NAME]... [--masks DIR] [--gt-meshes DIR]";
  spec.description =
      "For each held-out camera and frame, renders the run's animated scan and its template, projectively\n"
      "textured from the cameras the run used, into the held-out camera and compares with the real image:\n"
      "silhouette IoU and XOR error (% of the true silhouette area), and PSNR/SSIM computed inside the union\n"
      "of the true and the rendered silhouette (pixels outside both are background in both and are not\n"
      "counted); also, as psnr_box, the PSNR in the bounding box of that union with the pixels outside it\n"
      "black in both images (the Neural Body / ZJU-MoCap convention). The rendered views are seen over the\n"
      "held-out camera's clean plate (CAPTURE/background/<cam>.png) when the capture has one, as the camera\n"
      "saw the studio; --background black draws them over black. With the plates, the input cameras' colours\n"
      "are matched to each held-out camera's response: per camera RGB gains measured on the floor (z = 0) both\n"
      "plates show (--no-colour-match: off), and the outline is matted over the plate with a Gaussian of\n"
      "--edge-softness PX (default 0.5; 0 = a binary outline). The error split: psnr_inside, the PSNR\n"
      "inside the intersection of the two silhouettes (texture alone), and xor_error_share, the share of the\n"
      "squared error in the union on pixels only one silhouette covers (silhouette mismatch).\n"
      "Scan and template are textured alike; --best-k, --feather and --colour-balance set the texturing as\n"
      "for `confluent render` (metrics.json records it as texturing).\n"
      "--texture atlas scores the scan as an export would show it: its UV atlas (--atlas-size N, default 2048),\n"
      "each frame's projective texture baked into it (per held-out camera, with its colour match), encoded as\n"
      "H.264 (RUN/evaluation/atlas_<cam>.mp4, crf 18), decoded and rendered unlit with --atlas-samples N x N\n"
      "colour samples per pixel (default 4: MeshRenderer's mip-mapped sampling alone blurs over about two pixels;\n"
      "the demo, 2048 px: 1.1 dB below native at 4, 1.6 at 2, 3.1 at 1); the template stays projective.\n"
      "True silhouettes come from --masks DIR, else from the run's extracted masks (RUN/masks).\n"
      "With --gt-meshes DIR (meshes with the scan's topology, DIR/<frame>.ply) the scan's mean vertex error\n"
      "is reported. Writes RUN/metrics.json, metrics.csv, plots/*.png (per-frame metrics, error heat maps),\n"
      "evaluation/<cam>/<frame>.png (real | scan | template | difference) and report.html.\n"
      "CAPTURE and the held-out cameras default to the ones RUN/run.json records.";
  spec.min_positionals = 0;
  spec.max_positionals = 1;
  spec.options = {
      {"run", "RUN", "the run folder", false, true},
      {"heldout", "NAME", "held-out camera to score (default: the cameras the run held out)", true},
      {"masks", "DIR", "true silhouettes DIR/<cam>/<frame>.png (default: the run's masks)"},
      {"gt-meshes", "DIR", "ground-truth meshes DIR/<frame>.ply with the scan's topology: vertex error"},
      {"background", "plate|black", "what the rendered views are seen over (default plate: the held-out camera's clean plate)"},
      {"edge-softness", "PX", "Gaussian sigma of the outline's matting over the plate (default 0.5; 0 = binary)"},
      {"no-colour-match", "", "do not match the input cameras' colours to the held-out camera's (from the plates)"},
      {"frames", "A:B", "frame range, B exclusive (default: all)"},
      {"every", "N", "score every N-th frame (default 1)"},
      {"texture", "projective|atlas", "how the scan is textured (default projective; atlas: baked UV atlas video)"},
      {"atlas-size", "N", "--texture atlas: atlas width and height in texels (default 2048)"},
      {"atlas-samples", "N", "--texture atlas: N x N colour samples per pixel (default 4; 1 = MeshRenderer's own filtering)"},
      {"side-by-side-every", "N", "write side-by-side pictures every N scored frames (default 10; 0 = none)"},
  };
  for (const OptionSpec& option : TextureOptionSpecs()) spec.options.push_back(option);
  spec.run = RunEvaluate;
  return spec;
}

}  // namespace confluent::app
