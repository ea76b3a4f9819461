#pragma once
// INTERNAL (viewer/viewer_window.cc and viewer/view_draw.cc only): the state of `confluent view`'s window:
// the orbiting viewer camera, the capture behind the run, and the Viewer that the input handlers
// (viewer_window.cc) change and Draw (view_draw.cc) shows.

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "viewer/viewer_run.h"
#include "calib/capture.h"
#include "core/mesh.h"
#include "render/projective_texture.h"
#include "render/renderer.h"
#include "render/viewer_scene.h"

namespace confluent::view_internal {

constexpr double kPi = 3.14159265358979323846;
constexpr double kVerticalFovDeg = 40.0;  // of the viewer camera
constexpr int kTimelineHeightPx = 22;     // the timeline bar at the bottom of the window

enum class Mode { kTextured, kShaded, kWireframe, kWeights };

const char* ModeName(Mode mode);
// Parses --mode; throws UsageError for an unknown mode.
Mode ParseMode(const std::string& text);

// Distinct colours for the input cameras (frusta and blend weights).
Eigen::Vector3d CameraColor(int index);

// The orbiting viewer camera: spherical coordinates around a target point.
struct Orbit {
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  double distance_m = 3.0;
  double azimuth_deg = -90.0;  // 0 = camera on +x, -90 = camera on -y (in front)
  double elevation_deg = 15.0;

  Camera View(int width_px, int height_px) const {
    const double az = azimuth_deg * kPi / 180.0, el = elevation_deg * kPi / 180.0;
    const Eigen::Vector3d center =
        target + distance_m * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const double focal_px = 0.5 * height_px / std::tan(0.5 * kVerticalFovDeg * kPi / 180.0);
    return LookAtCamera("view", center, target, width_px, height_px, focal_px);
  }
};

// The initial view: looks at the centre of `mesh`'s bounding box from the front (-y), 15 degrees
// above, from where the bounding sphere fills the vertical field of view with a margin.
Orbit InitialOrbit(const Mesh& mesh);

// A camera with its image scaled by `scale` (pixel centres kept consistent).
Camera ScaledCamera(const Camera& camera, double scale);

// Lets offscreen EGL work run on this thread: releases the window's (GLX) context, and on exit
// releases EGL and makes the window's context current again (libglvnd allows one API per thread).
class OffscreenScope {
 public:
  explicit OffscreenScope(GLFWwindow* window) : window_(window) { glfwMakeContextCurrent(nullptr); }
  ~OffscreenScope() {
    ReleaseCurrentEglContext();
    glfwMakeContextCurrent(window_);
  }
  OffscreenScope(const OffscreenScope&) = delete;
  OffscreenScope& operator=(const OffscreenScope&) = delete;

 private:
  GLFWwindow* window_;
};

// The capture behind the run: cameras used for texturing, frames, masks.
struct CaptureState {
  std::optional<Capture> capture;
  std::vector<int> used;  // indices into the rig of the cameras used for texturing
  std::string error;      // why there is no capture
};

// Opens the run's capture; failures land in CaptureState::error.
CaptureState OpenCaptureFor(const ViewerRun& run);

// Everything the window shows and the input handlers change.
struct Viewer {
  const ViewerRun* run = nullptr;
  FrameCache* frames = nullptr;
  CaptureState* capture = nullptr;
  GLFWwindow* window = nullptr;
  std::unique_ptr<ViewerScene> scene;

  int frame = 0;
  Mode mode = Mode::kShaded;
  bool show_frusta = false;
  bool playing = false;
  double fps = 25.0;
  Orbit orbit;
  Eigen::Vector3d background = Eigen::Vector3d(0.12, 0.12, 0.14);

  // Mouse state.
  bool rotating = false, zooming = false, scrubbing = false;
  double last_x = 0.0, last_y = 0.0;

  // What the GPU holds.
  int uploaded_frame = -1;
  bool uploaded_weights = false;
  bool frusta_uploaded = false;
  std::shared_ptr<const Mesh> mesh;  // the current frame's mesh (null when missing)
  std::string frame_error;
  std::string note;                  // why the mode fell back (set by every Draw), in the title
  std::string message;               // last key action's result (saved screenshot), in the title
  bool dirty = true;
  int drawn_frames = 0;

  // Offscreen texturing and visibility (EGL), created on first use.
  std::unique_ptr<ProjectiveTexturer> texturer;
  int texturer_vertices = -1;
  int texturer_frame = -1;
  std::string texture_error;
  std::unique_ptr<MeshRenderer> depth_renderer;
  int depth_frame = -1;
  std::vector<Camera> depth_cameras;  // used cameras at reduced resolution
  std::vector<Image> depth_maps;

  void SetFrame(int new_frame) {
    new_frame = std::clamp(new_frame, run->first_frame, run->last_frame);
    if (new_frame != frame) {
      frame = new_frame;
      dirty = true;
    }
  }
  void Step(int delta) {
    const int n = run->num_frames();
    SetFrame(run->first_frame + ((frame - run->first_frame + delta) % n + n) % n);
  }
};

Viewer* GetViewer(GLFWwindow* window);

// Frame under window x (in framebuffer pixels) on the timeline.
int TimelineFrame(const Viewer& viewer, double x, int width_px);

// Cursor position in framebuffer pixels.
void CursorInFramebuffer(GLFWwindow* window, double* x, double* y);

// Loads the current frame's mesh and uploads it (and its colours) when it changed.
void UpdateGeometry(Viewer& viewer);

// Draws the current state into the window's back buffer (view_draw.cc).
void Draw(Viewer& viewer, bool with_timeline);

}  // namespace confluent::view_internal
