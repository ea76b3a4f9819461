// confluent render [CAPTURE] --run RUN --out DIR: the arguments of the novel views of a run
// (pipeline/novel_views.h) and their summary on the terminal.

#include <cstdio>
#include <string>

#include "app/commands.h"
#include "app/texture_args.h"
#include "core/error.h"
#include "pipeline/finished_run.h"
#include "pipeline/novel_views.h"

namespace confluent::app {
namespace {

int RunRender(const ParsedArgs& args, const Context& context) {
  const FinishedRun finished = OpenFinishedRun(args.get("run"), args.positionals().empty() ? "" : args.positionals()[0]);
  NovelViewOptions options;
  options.geometry = args.get("geometry", options.geometry);
  if (options.geometry != "scan" && options.geometry != "template")
    throw UsageError("--geometry: expected scan or template, got '" + options.geometry + "'");
  options.format = args.get("format", options.format);
  if (options.format != "png" && options.format != "exr")
    throw UsageError("--format: expected png or exr, got '" + options.format + "'");
  options.width = args.get_int("width", 0);
  options.height = args.get_int("height", 0);
  if ((options.width > 0) != (options.height > 0) || options.width < 0 || options.height < 0 || options.width > 8192 ||
      options.height > 8192)
    throw UsageError("--width and --height: give both, each in 1..8192");
  options.path = args.get("path", options.path);
  options.path_frames = args.get_int("path-frames", 0);
  if (options.path_frames < 0) throw UsageError("--path-frames: must be >= 0");
  options.write_mp4 = args.has("mp4");
  options.fps = args.get_double("fps", 0.0);
  if (args.has("fps") && !(options.fps > 0.0)) throw UsageError("--fps: must be > 0");
  options.excluded = args.get_all("exclude-camera");
  options.texture_from_held_out = args.has("texture-from-held-out");
  options.over_plate = args.has("over-plate");
  options.edge_softness_px = args.get_double("edge-softness", options.edge_softness_px);
  if (!(options.edge_softness_px >= 0.0 && options.edge_softness_px <= 5.0))
    throw UsageError("--edge-softness: must be within [0, 5] pixels");
  options.texturing = TextureOptionsFromArgs(args);

  CaptureOptions capture_options;
  capture_options.check_every_image_header = false;
  const Capture capture = Capture::Open(finished.capture_root, capture_options);
  const FrameRange range = ParseFrameRange(args.get("frames"), capture.num_frames());
  const NovelViewSummary summary =
      RenderNovelViews(finished, capture, range, args.get("out"), options, context.make_progress());

  for (const std::string& warning : summary.warnings)
    std::fprintf(stderr, "confluent render: warning: %s\n", warning.c_str());
  std::printf("rendered %d %dx%d view(s) '%s' of the %s (%d of %d capture cameras texturing) to %s/\n", summary.written,
              summary.width, summary.height, summary.view.c_str(), options.geometry.c_str(), summary.texturing_cameras,
              capture.rig().size(), summary.view_dir.c_str());
  std::printf("time per frame (median): texture setup %.1f ms, novel view %.1f ms\n", summary.median_setup_ms,
              summary.median_render_ms);
  if (!summary.video_path.empty())
    std::printf("video: %s (%d frames at %g fps)\n", summary.video_path.c_str(), summary.video_frames, summary.fps);
  if (!summary.missing.empty()) {
    std::string list;
    for (int frame : summary.missing) list += (list.empty() ? "" : " ") + std::to_string(frame);
    std::printf("missing %s meshes for %zu frame(s), not rendered: %s\n", options.geometry.c_str(),
                summary.missing.size(), list.c_str());
  }
  return 0;
}

}  // namespace

CommandSpec MakeRenderCommand() {
  CommandSpec spec;
  spec.name = "render";
  spec.summary = "render novel views of a run's 3D video (projective texturing) to images and MP4";
  spec.usage = "[CAPTURE] --run RUN --out DIR [--path orbit|cameras:A,B,..|fixed:NAME|fixed:CALIB_DIR/NAME|bullet:FRAME] [options]";
  spec.description =
      "Textures the run's animated scan (RUN/scan/<frame>.ply; --geometry template for RUN/template/) from\n"
      "the capture's camera images: per-camera visibility from depth maps, unstructured-lumigraph weights\n"
      "over the best k cameras, feathering near silhouette edges and depth discontinuities, and the mesh's\n"
      "own colours where no camera sees the surface. Masks come from RUN/masks/ (else CAPTURE/masks/).\n"
      "Writes DIR/<view>/<frame:06d>.png (or .exr, linear) and with --mp4 DIR/<view>.mp4 (H.264).\n"
      "Paths: orbit (one turn around the actor over the frames), cameras:NAME,... (a smooth path through\n"
      "those input cameras), fixed:NAME or fixed:CALIB_DIR/NAME (a camera of the capture or of another\n"
      "intri.yml/extri.yml, e.g. a held-out camera), bullet:FRAME (frozen time, a sweep around the ring).\n"
      "--over-plate draws a capture camera's fixed view over its clean plate with the input cameras'\n"
      "colours matched to it (as `confluent evaluate` scores held-out views).\n"
      "Frames without geometry are skipped and listed. CAPTURE defaults to the one RUN/run.json names; the\n"
      "cameras the run held out never texture the view unless --texture-from-held-out is given.";
  spec.min_positionals = 0;
  spec.max_positionals = 1;
  spec.options = {
      {"run", "RUN", "the run folder (scan/, template/, masks/)", false, true},
      {"out", "DIR", "output folder (e.g. RUN/renders)", false, true},
      {"path", "PATH", "orbit (default), cameras:A,B,..., fixed:NAME, fixed:CALIB_DIR/NAME or bullet:FRAME"},
      {"geometry", "scan|template", "which meshes to texture (default scan)"},
      {"exclude-camera", "NAME", "do not texture from this camera (the run's held-out cameras never do)", true},
      {"texture-from-held-out", "", "texture from the cameras the run held out too (prints a warning)"},
      {"frames", "A:B", "frame range, B exclusive (default: all frames)"},
      {"format", "png|exr", "image format (default png)"},
      {"mp4", "", "also write DIR/<view>.mp4 (needs ffmpeg)"},
      {"fps", "F", "video frame rate (default: the run's, else 25)"},
      {"width", "W", "output width (with --height; default: the cameras' size)"},
      {"height", "H", "output height"},
      {"path-frames", "N", "cameras on the path (default: one per frame; bullet time: 60)"},
      {"over-plate", "", "with --path fixed:NAME: draw over that camera's clean plate, input colours matched to it"},
      {"edge-softness", "PX", "with --over-plate: Gaussian sigma of the outline's matting (default 0.5; 0 = binary)"},
  };
  for (const OptionSpec& option : TextureOptionSpecs()) spec.options.push_back(option);
  spec.run = RunRender;
  return spec;
}

}  // namespace confluent::app
