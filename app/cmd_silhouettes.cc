// confluent silhouettes CAPTURE [--out DIR] [--frames A:B] [--method M]: masks, overlay contact
// sheets and a summary of every camera's silhouettes.

#include <cstdio>
#include <filesystem>

#include "app/commands.h"
#include "calib/capture.h"
#include "core/error.h"
#include "pipeline/frame_range.h"
#include "pipeline/silhouette_folder.h"

namespace confluent::app {
namespace fs = std::filesystem;

namespace {

int RunSilhouettes(const ParsedArgs& args, const Context& context) {
  const std::string root = args.positionals()[0];
  const std::string out_dir = args.get("out", (fs::path(root) / "masks").string());
  SilhouetteFolderOptions folder_options;
  SilhouetteOptions& options = folder_options.silhouettes;
  options.method = ParseSilhouetteMethod(args.get("method", "auto"));
  options.threads = args.get_int("threads", 2);
  options.person_prior.use = ParsePersonPriorUse(args.get("person-prior", "auto"));
  if (args.has("greenness")) options.chroma.greenness = args.get_double("greenness", 0.0);
  options.Check();
  folder_options.overlays = !args.has("no-overlays");
  folder_options.overlay_width = args.get_int("overlay-width", folder_options.overlay_width);
  if (folder_options.overlay_width < 32 || folder_options.overlay_width > 4096)
    throw UsageError("--overlay-width: must be within [32, 4096]");
  folder_options.compare_dir = args.get("compare");

  CaptureOptions capture_options;
  capture_options.check_every_image_header = false;
  const Capture capture = Capture::Open(root, capture_options);
  const FrameRange range = ParseFrameRange(args.get("frames"), capture.num_frames());

  const SilhouetteFolderSummary result =
      ExtractSilhouettesToFolder(capture, range, out_dir, folder_options, context.make_progress());
  for (const std::string& line : result.lines) std::printf("%s\n", line.c_str());
  for (const std::string& warning : result.extraction.warnings)
    std::fprintf(stderr, "confluent silhouettes: warning: %s\n", warning.c_str());
  std::printf("%d camera-frame(s) flagged; masks in %s%s, summary in %s\n", result.extraction.num_flagged(),
              out_dir.c_str(), result.overlay_dir.empty() ? "" : (", contact sheets in " + result.overlay_dir).c_str(),
              result.summary_path.c_str());
  return 0;
}

}  // namespace

CommandSpec MakeSilhouettesCommand() {
  CommandSpec spec;
  spec.name = "silhouettes";
  spec.summary = "cut the actor out of every frame: masks, overlay contact sheets, summary";
  spec.usage = "CAPTURE [--out DIR] [--frames A:B] [--method auto|plate|green|learned|mog2|person]";
  spec.description =
      "Writes DIR/<cam>/<frame>.png (0/255 masks; DIR defaults to CAPTURE/masks), DIR/overlays/<frame>.png\n"
      "(every camera's image with its mask contour, tiled) and DIR/summary.json (per camera the method and\n"
      "thresholds; per camera and frame the foreground fraction and flags: empty, full, touching the border,\n"
      "sudden jump in area). Methods: plate = clean plate background/<cam>.png with a brightness/chromaticity\n"
      "model that ignores shadows; green = chroma key; learned = temporal median of the video; mog2 = OpenCV's\n"
      "mixture model; auto = plate if present, else green if the frames look green, else learned. A missing\n"
      "plate falls back to the learned background with a warning. Without a plate, a person prior (BlazePose)\n"
      "keeps the learned background's masks near the person it finds (--person-prior).";
  spec.min_positionals = spec.max_positionals = 1;
  spec.options = {
      {"out", "DIR", "output folder (default CAPTURE/masks)"},
      {"frames", "A:B", "frame range, B exclusive (default: all frames)"},
      {"method", "NAME", "auto (default), plate, green, learned, mog2 or person (a learned person prior, BlazePose)"},
      {"person-prior", "MODE", "auto (default: when installed), on or off: the person prior for cameras without a plate"},
      {"greenness", "X", "chroma-key threshold in (0, 1) instead of the automatic one"},
      {"threads", "N", "cameras processed in parallel (default 2)"},
      {"compare", "DIR", "reference masks DIR/<cam>/<frame>.png: report IoU per camera (and in the summary)"},
      {"overlay-width", "PX", "width of each camera's tile in the contact sheets (default 480)"},
      {"no-overlays", "", "do not write contact sheets"},
  };
  spec.run = RunSilhouettes;
  return spec;
}

}  // namespace confluent::app
