#pragma once
// The web player of an export: a static page (three.js, embedded into the binary at build time
// from export/player/ and its npm-installed three.js) that plays scene.glb with the atlas video
// as its texture. Serve the export folder from any web server and open player/index.html; its
// query parameters (a fixed camera and frame, for screenshots) are described in
// export/player/player.js.

#include <string>
#include <vector>

#include "calib/camera.h"

namespace confluent {

struct PlayerOptions {
  // URLs of the scene and the atlas video, relative to the player folder (or absolute URLs).
  std::string scene_url = "../scene.glb";
  std::string video_url = "../atlas.mp4";
  // Throws UsageError when a URL is empty.
  void Check() const;
};

// Writes the player into folder `dir` (created when missing): index.html, player.js,
// config.json (the options' URLs) and three/ (three.js's modules, its GLTFLoader,
// OrbitControls and meshopt decoder, and its licence). Each file is written atomically.
// Returns the paths written, relative to `dir`. Throws UsageError for bad options and
// OutputError naming the file that could not be written.
std::vector<std::string> WritePlayer(const std::string& dir, const PlayerOptions& options = {});

// The query string (without '?') that makes player/index.html render frame `frame` from
// `camera` at its resolution, pause and set window.playerReady: fx, fy, cx, cy, width, height,
// R (row-major) and t of the cam_from_world transform, and frame, at full double precision.
// The page renders an ideal pinhole: lens distortion and skew are not applied. Throws
// UsageError for a negative frame.
std::string PlayerCameraQuery(const Camera& camera, int frame);

}  // namespace confluent
