// confluent export RUN --out DIR [--capture CAPTURE]: the arguments of a run's export
// (pipeline/export_run.h) and its summary on the terminal.

#include <algorithm>
#include <cstdio>
#include <string>

#include "app/commands.h"
#include "app/texture_args.h"
#include "calib/capture.h"
#include "core/error.h"
#include "pipeline/export_run.h"
#include "pipeline/finished_run.h"
#include "pipeline/frame_range.h"

namespace confluent::app {
namespace {

void PrintStream(const char* label, const ExportedStream& stream) {
  std::printf("%-6s %s: %d vertices, %d triangles, %.1f MB; %s: %d px atlas, %.1f MB; %.2f Mbit/s\n", label,
              stream.glb_path.c_str(), stream.glb.vertices, stream.glb.triangles, stream.glb.bytes / 1e6,
              stream.video_path.c_str(), stream.atlas_px, stream.video_bytes / 1e6, stream.megabits_per_second);
}

int RunExport(const ParsedArgs& args, const Context& context) {
  const FinishedRun finished = OpenFinishedRun(args.positionals()[0], args.get("capture", ""));
  ExportOptions options;
  options.atlas.size_px = args.get_int("atlas-size", options.atlas.size_px);
  options.stream_triangles = args.get_int("decimate", 0);
  options.stream_atlas_px = args.get_int("stream-atlas-size", std::min(options.stream_atlas_px, options.atlas.size_px));
  options.video.crf = args.get_int("crf", options.video.crf);
  options.stream_crf = args.get_int("stream-crf", options.stream_crf);
  options.fps = args.get_double("fps", 0.0);
  if (args.has("fps") && !(options.fps > 0.0)) throw UsageError("--fps: must be > 0");
  options.gltf.meshopt_compression = !args.has("no-meshopt");
  options.excluded = args.get_all("exclude-camera");
  options.texture_from_held_out = args.has("texture-from-held-out");
  options.player = !args.has("no-player");
  options.ply = args.has("ply");
  options.obj = args.has("obj");
  options.pc2 = args.has("pc2");
  options.texturing = TextureOptionsFromArgs(args);

  CaptureOptions capture_options;
  capture_options.check_every_image_header = false;
  const Capture capture = Capture::Open(finished.capture_root, capture_options);
  const FrameRange range = ParseFrameRange(args.get("frames"), capture.num_frames());
  const std::string out = args.get("out");
  const ExportSummary summary = ExportRun(finished, capture, range, out, options, context.make_progress());

  for (const std::string& warning : summary.warnings)
    std::fprintf(stderr, "confluent export: warning: %s\n", warning.c_str());
  std::printf("exported frames %d:%d (%d at %g fps) of %s, textured from %d of %d cameras, to %s/\n",
              summary.first_frame, summary.first_frame + summary.frames, summary.frames, summary.fps,
              finished.folder.root.c_str(), summary.texturing_cameras, capture.rig().size(), out.c_str());
  std::printf("atlas  %d px: %d charts, texel use %.2f, stretch %.3f (max %.2f); bake %.0f ms per frame (median)\n",
              options.atlas.size_px, summary.atlas.charts, summary.atlas.texel_use, summary.atlas.stretch_mean,
              summary.atlas.stretch_max, summary.median_bake_ms);
  PrintStream("full", summary.full);
  if (!summary.stream.glb_path.empty()) PrintStream("stream", summary.stream);
  if (options.player)
    std::printf("player: serve %s (e.g. python3 -m http.server -d %s) and open /player/index.html\n", out.c_str(),
                out.c_str());
  return 0;
}

}  // namespace

CommandSpec MakeExportCommand() {
  CommandSpec spec;
  spec.name = "export";
  spec.summary = "export a run's 3D video: glTF (scene.glb), atlas video, web player, mesh sequences";
  spec.usage = "RUN --out DIR [--capture CAPTURE] [--frames A:B] [--decimate N] [--atlas-size PX] [--ply] [--obj] [--pc2]";
  spec.description =
      "Gives the run's scan a UV atlas (charts along the body segments, flattened and packed once), bakes\n"
      "every frame's projective texture from the capture's cameras into it (as `render` blends them; the\n"
      "scan's colours where no camera sees the surface) and writes:\n"
      "  DIR/scene.glb     glTF 2.0: the animated scan (one node per frame, shown in turn), atlas UVs, the\n"
      "                    first atlas frame as base colour; quantised, meshopt-compressed (--no-meshopt\n"
      "                    for importers without EXT_meshopt_compression, such as Blender's)\n"
      "  DIR/atlas.mp4     the atlas per frame, H.264, frames aligned with the mesh frames; DIR/atlas.png\n"
      "  DIR/player/       a web page that plays scene.glb with atlas.mp4 as its texture (three.js\n"
      "                    included): serve DIR with any web server and open player/index.html\n"
      "  DIR/stream/       with --decimate N: the same with the mesh decimated to about N triangles and a\n"
      "                    smaller atlas (--stream-atlas-size, default 1024)\n"
      "  DIR/ply/, DIR/obj/, DIR/scan.pc2 + rest.ply   with --ply, --obj (atlas UVs, atlas.png), --pc2\n"
      "  DIR/export.json   sizes, bitrates and the atlas's figures\n"
      "Every frame of the range needs its scan (RUN/scan/<frame>.ply). The capture is the one\n"
      "RUN/run.json names unless --capture; the cameras the run held out never texture unless\n"
      "--texture-from-held-out.";
  spec.min_positionals = 1;
  spec.max_positionals = 1;
  spec.options = {
      {"capture", "CAPTURE", "the capture the run was made from (default: the one RUN/run.json names)"},
      {"out", "DIR", "output folder", false, true},
      {"frames", "A:B", "frame range, B exclusive (default: all frames)"},
      {"atlas-size", "PX", "atlas width and height (default 2048)"},
      {"decimate", "N", "also write DIR/stream/ with the mesh decimated to about N triangles"},
      {"stream-atlas-size", "PX", "the stream variant's atlas size (default 1024)"},
      {"crf", "N", "H.264 quality of the atlas video, 0..51 (default 18)"},
      {"stream-crf", "N", "H.264 quality of the stream variant's atlas video (default 23)"},
      {"fps", "F", "frame rate of the videos and the animation (default: the run's, else 25)"},
      {"no-meshopt", "", "write scene.glb without EXT_meshopt_compression (larger; Blender imports it)"},
      {"no-player", "", "do not write the web player"},
      {"ply", "", "also write DIR/ply/<frame>.ply with the scan's colours"},
      {"obj", "", "also write DIR/obj/<frame>.obj with the atlas UVs and atlas.png as texture"},
      {"pc2", "", "also write DIR/scan.pc2 and DIR/rest.ply (Blender's Mesh Cache modifier)"},
      {"exclude-camera", "NAME", "do not texture from this camera (the run's held-out cameras never do)", true},
      {"texture-from-held-out", "", "texture from the cameras the run held out too (prints a warning)"},
  };
  for (const OptionSpec& option : TextureOptionSpecs()) spec.options.push_back(option);
  spec.run = RunExport;
  return spec;
}

}  // namespace confluent::app
