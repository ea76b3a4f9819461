#pragma once
// `confluent view`: an interactive GLFW window on a run's 3D video (the animated scan, or the
// posed template), projectively textured from the capture, with camera frusta, blend weights, a
// timeline and screenshots. The window's state is in view_state.h, drawing it in view_draw.cc.

#include <optional>
#include <string>

#include "viewer/viewer_run.h"

namespace confluent {

struct ViewerOptions {
  int width = 960, height = 720;        // of the window
  double fps = 0.0;                     // playback rate; 0: the run's (else 25)
  bool show_frusta = false;             // the capture's cameras
  bool play = false;                    // start playing
  std::optional<int> frame;             // the first frame shown; default: the run's first
  std::string mode;                     // textured, shaded, wireframe or weights; "": textured with a capture
  std::optional<double> azimuth_deg;    // of the orbiting view; default: facing the front
  std::optional<double> elevation_deg;  // -85..85
  double zoom = 1.0;                    // the view's distance, times
  std::string screenshot;               // draw one frame into this PNG and return (no interaction)
  int exit_after_frames = 0;            // stop after drawing N frames (scripted smoke runs); 0: when closed
};

// Opens the window on `run` and runs it until it is closed (or the screenshot is written).
// Throws Error when no window can be opened (naming the missing display), UsageError for bad
// options, InputError for a frame that cannot be read.
void RunViewer(const ViewerRun& run, const ViewerOptions& options);

}  // namespace confluent
