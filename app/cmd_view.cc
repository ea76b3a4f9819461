// confluent view RUN: the arguments of the interactive viewer (viewer/viewer_window.h).

#include <string>

#include "app/commands.h"
#include "core/error.h"
#include "viewer/viewer_window.h"

namespace confluent::app {
namespace {

// "WxH" -> width, height.
void ParseSize(const std::string& text, int* width, int* height) {
  const auto x = text.find('x');
  try {
    if (x == std::string::npos) throw std::invalid_argument("no x");
    std::size_t used = 0;
    *width = std::stoi(text.substr(0, x), &used);
    if (used != x) throw std::invalid_argument("width");
    *height = std::stoi(text.substr(x + 1), &used);
    if (used != text.size() - x - 1) throw std::invalid_argument("height");
  } catch (const std::exception&) {
    throw UsageError("--size: expected WIDTHxHEIGHT such as 960x720, got '" + text + "'");
  }
  if (*width < 16 || *height < 16 || *width > 8192 || *height > 8192)
    throw UsageError("--size: width and height must be in 16..8192, got '" + text + "'");
}

int RunView(const ParsedArgs& args, const Context&) {
  ViewerOptions options;
  ParseSize(args.get("size", "960x720"), &options.width, &options.height);
  options.exit_after_frames = args.get_int("exit-after-frames", 0);
  if (options.exit_after_frames < 0) throw UsageError("--exit-after-frames: must be >= 0");
  options.fps = args.get_double("fps", 0.0);
  if (args.has("fps") && !(options.fps > 0.0 && options.fps <= 240.0)) throw UsageError("--fps: must be in (0, 240]");
  options.show_frusta = args.has("frusta");
  options.play = args.has("play");
  if (args.has("frame")) options.frame = args.get_int("frame", 0);
  options.mode = args.get("mode");
  if (args.has("azimuth")) options.azimuth_deg = args.get_double("azimuth", 0.0);
  if (args.has("elevation")) options.elevation_deg = args.get_double("elevation", 0.0);
  options.zoom = args.get_double("zoom", 1.0);
  options.screenshot = args.get("screenshot");
  RunViewer(OpenViewerRun(args.positionals()[0], args.get("capture")), options);
  return 0;
}

}  // namespace

CommandSpec MakeViewCommand() {
  CommandSpec spec;
  spec.name = "view";
  spec.summary = "interactive viewer of a run's 3D video (GLFW window; needs a display)";
  spec.usage = "RUN [--capture CAPTURE] [--screenshot FILE --frame N --mode textured|shaded|wireframe|weights]";
  spec.description =
      "Plays RUN/scan/<frame>.ply (or RUN/template/<frame>.ply when there is no scan/) in a window. The capture\n"
      "named in RUN/run.json (or --capture) textures the meshes projectively from its cameras, except the\n"
      "run's excluded cameras. Frames are loaded on demand; a missing frame is named in the window title.\n"
      "\n"
      "Mouse: left drag orbits, right drag or the wheel zooms, a click or drag on the timeline bar scrubs.\n"
      "Keys: space play/pause, left/right arrows step (Home/End jump), T textured, S shaded (vertex colours,\n"
      "lit), W wireframe, B blend weights (each vertex in the colour of the camera with the largest weight),\n"
      "C camera frusta (used cameras in their blend-weight colour, excluded ones grey), P save a screenshot\n"
      "(confluent-view-<frame>.png in the working folder), Q or Esc quit.\n"
      "\n"
      "The initial view looks at the centre of the first readable frame's bounding box from the front (-y),\n"
      "15 degrees above, at 1.2 bounding-sphere radii / sin(20 deg), with a 40 degree vertical field of view.\n"
      "--screenshot FILE renders --frame N in --mode in that view (without the timeline), writes a PNG of\n"
      "--size and exits. Without a display, run it under xvfb-run.";
  spec.min_positionals = 1;
  spec.max_positionals = 1;
  spec.options = {
      {"capture", "CAPTURE", "capture folder for texturing and frusta (default: the one in run.json)"},
      {"screenshot", "FILE", "render one frame to FILE (PNG) and exit"},
      {"frame", "N", "frame to show first (default: the first frame)"},
      {"mode", "MODE", "textured (default with a capture), shaded (default without), wireframe or weights"},
      {"frusta", "", "show the capture's camera frusta from the start"},
      {"azimuth", "DEG", "initial view azimuth around the vertical axis (default -90: from -y; 0: from +x)"},
      {"elevation", "DEG", "initial view elevation (default 15)"},
      {"zoom", "F", "initial view distance times F (default 1; 3 shows a camera ring)"},
      {"size", "WxH", "window size in pixels (default 960x720)"},
      {"fps", "F", "playback rate (default: the run's, else 25)"},
      {"play", "", "start playing"},
      {"exit-after-frames", "K", "quit after drawing K frames (scripted smoke tests)"},
  };
  spec.run = RunView;
  return spec;
}

}  // namespace confluent::app
