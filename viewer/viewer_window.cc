#include "viewer/viewer_window.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/frame_range.h"
#include "pipeline/run_manifest.h"
#include "calib/capture.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_ops.h"
#include "render/projective_texture.h"
#include "render/renderer.h"
#include "render/viewer_scene.h"
#include "viewer/view_state.h"

namespace confluent {
namespace view_internal {

const char* ModeName(Mode mode) {
  switch (mode) {
    case Mode::kTextured: return "textured";
    case Mode::kShaded: return "shaded";
    case Mode::kWireframe: return "wireframe";
    case Mode::kWeights: return "blend weights";
  }
  return "";
}

Mode ParseMode(const std::string& text) {
  if (text == "textured") return Mode::kTextured;
  if (text == "shaded") return Mode::kShaded;
  if (text == "wireframe") return Mode::kWireframe;
  if (text == "weights") return Mode::kWeights;
  throw UsageError("--mode: expected textured, shaded, wireframe or weights, got '" + text + "'");
}

// Distinct colours for the input cameras (frusta and blend weights).
Eigen::Vector3d CameraColor(int index) {
  static const double kPalette[][3] = {{0.90, 0.30, 0.25}, {0.25, 0.70, 0.30}, {0.25, 0.45, 0.90}, {0.95, 0.75, 0.20},
                                       {0.70, 0.35, 0.85}, {0.20, 0.80, 0.80}, {0.95, 0.50, 0.75}, {0.60, 0.45, 0.25},
                                       {0.55, 0.85, 0.30}, {0.35, 0.35, 0.65}};
  const auto& c = kPalette[index % 10];
  return {c[0], c[1], c[2]};
}

// The initial view: looks at the centre of `mesh`'s bounding box from the front (-y), 15 degrees
// above, from where the bounding sphere fills the vertical field of view with a margin.
Orbit InitialOrbit(const Mesh& mesh) {
  const Eigen::AlignedBox3d box = BoundingBox(mesh);
  Orbit orbit;
  orbit.target = box.center();
  const double radius = std::max(0.5 * box.diagonal().norm(), 1e-3);
  orbit.distance_m = 1.2 * radius / std::sin(0.5 * kVerticalFovDeg * kPi / 180.0);
  return orbit;
}

// A camera with its image scaled by `scale` (pixel centres kept consistent).
Camera ScaledCamera(const Camera& camera, double scale) {
  Camera scaled = camera;
  scaled.width = std::max(1, static_cast<int>(std::lround(camera.width * scale)));
  scaled.height = std::max(1, static_cast<int>(std::lround(camera.height * scale)));
  const double sx = static_cast<double>(scaled.width) / camera.width;
  const double sy = static_cast<double>(scaled.height) / camera.height;
  scaled.K(0, 0) *= sx;
  scaled.K(0, 1) *= sx;
  scaled.K(1, 1) *= sy;
  scaled.K(0, 2) = (camera.K(0, 2) + 0.5) * sx - 0.5;
  scaled.K(1, 2) = (camera.K(1, 2) + 0.5) * sy - 0.5;
  return scaled;
}

CaptureState OpenCaptureFor(const ViewerRun& run) {
  CaptureState state;
  if (run.capture.empty()) {
    state.error = "no capture (run.json names none; give --capture)";
    return state;
  }
  try {
    CaptureOptions options;
    options.check_every_image_header = false;
    state.capture = Capture::Open(run.capture, options);
    const Rig& rig = state.capture->rig();
    for (int i = 0; i < rig.size(); ++i)
      if (std::find(run.excluded_cameras.begin(), run.excluded_cameras.end(), rig.cameras[i].name) ==
          run.excluded_cameras.end())
        state.used.push_back(i);
  } catch (const std::exception& e) {
    state.capture.reset();
    state.error = std::string("capture unavailable: ") + e.what();
  }
  return state;
}

Viewer* GetViewer(GLFWwindow* window) { return static_cast<Viewer*>(glfwGetWindowUserPointer(window)); }

// Frame under window x (in framebuffer pixels) on the timeline.
int TimelineFrame(const Viewer& viewer, double x, int width_px) {
  const double t = std::clamp(x / std::max(1, width_px), 0.0, 1.0);
  const int n = viewer.run->num_frames();
  return viewer.run->first_frame + std::min(n - 1, static_cast<int>(t * n));
}

// Cursor position in framebuffer pixels.
void CursorInFramebuffer(GLFWwindow* window, double* x, double* y) {
  int window_w = 1, window_h = 1, fb_w = 1, fb_h = 1;
  glfwGetWindowSize(window, &window_w, &window_h);
  glfwGetFramebufferSize(window, &fb_w, &fb_h);
  glfwGetCursorPos(window, x, y);
  *x *= static_cast<double>(fb_w) / std::max(1, window_w);
  *y *= static_cast<double>(fb_h) / std::max(1, window_h);
}

// Loads the current frame's mesh and uploads it (and its colours) when it changed.
void UpdateGeometry(Viewer& viewer) {
  if (viewer.uploaded_frame == viewer.frame) return;
  viewer.mesh = viewer.frames->Get(viewer.frame, &viewer.frame_error);
  if (viewer.mesh) viewer.scene->SetMesh(*viewer.mesh);
  viewer.uploaded_frame = viewer.frame;
  viewer.uploaded_weights = false;
}

}  // namespace view_internal

namespace {
namespace fs = std::filesystem;
using namespace view_internal;

void UpdateTitle(Viewer& viewer) {
  std::string title = "confluent view " + fs::path(viewer.run->root).filename().string() + " - " +
                      viewer.run->mesh_kind + " frame " + std::to_string(viewer.frame) + " of " +
                      std::to_string(viewer.run->first_frame) + ".." + std::to_string(viewer.run->last_frame) + " - " +
                      ModeName(viewer.mode) + (viewer.playing ? " - playing" : "");
  if (!viewer.frame_error.empty()) title += " - " + viewer.frame_error;
  if (!viewer.note.empty()) title += " - " + viewer.note;
  if (!viewer.message.empty()) title += " - " + viewer.message;
  glfwSetWindowTitle(viewer.window, title.c_str());
}

// A file name in the working folder that does not exist yet.
std::string ScreenshotName(int frame) {
  for (int i = 0;; ++i) {
    const std::string name =
        "confluent-view-" + FrameStem(frame) + (i == 0 ? std::string() : "-" + std::to_string(i)) + ".png";
    if (!fs::exists(name)) return name;
  }
}

void SaveScreenshot(Viewer& viewer, const std::string& path) {
  int width = 1, height = 1;
  glfwGetFramebufferSize(viewer.window, &width, &height);
  WriteImage(path, viewer.scene->ReadPixels(width, height));
}

void OnKey(GLFWwindow* window, int key, int, int action, int) {
  if (action != GLFW_PRESS && action != GLFW_REPEAT) return;
  Viewer& viewer = *GetViewer(window);
  viewer.dirty = true;
  viewer.message.clear();
  switch (key) {
    case GLFW_KEY_SPACE: viewer.playing = !viewer.playing; break;
    case GLFW_KEY_RIGHT: viewer.playing = false; viewer.Step(1); break;
    case GLFW_KEY_LEFT: viewer.playing = false; viewer.Step(-1); break;
    case GLFW_KEY_HOME: viewer.SetFrame(viewer.run->first_frame); break;
    case GLFW_KEY_END: viewer.SetFrame(viewer.run->last_frame); break;
    case GLFW_KEY_T: viewer.mode = Mode::kTextured; break;
    case GLFW_KEY_S: viewer.mode = Mode::kShaded; break;
    case GLFW_KEY_W: viewer.mode = Mode::kWireframe; break;
    case GLFW_KEY_B: viewer.mode = Mode::kWeights; break;
    case GLFW_KEY_C: viewer.show_frusta = !viewer.show_frusta; break;
    case GLFW_KEY_P: {
      // The next redraw leaves the picture in the back buffer; draw it now without the timeline.
      Draw(viewer, false);
      const std::string name = ScreenshotName(viewer.frame);
      try {
        SaveScreenshot(viewer, name);
        viewer.message = "saved " + fs::absolute(name).string();
      } catch (const std::exception& e) {
        viewer.message = std::string("screenshot failed: ") + e.what();
      }
      break;
    }
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q: glfwSetWindowShouldClose(window, GLFW_TRUE); break;
    default: viewer.dirty = false; break;
  }
}

void OnMouseButton(GLFWwindow* window, int button, int action, int) {
  Viewer& viewer = *GetViewer(window);
  double x = 0.0, y = 0.0;
  CursorInFramebuffer(window, &x, &y);
  int width = 1, height = 1;
  glfwGetFramebufferSize(window, &width, &height);
  viewer.last_x = x;
  viewer.last_y = y;
  const bool press = action == GLFW_PRESS;
  if (button == GLFW_MOUSE_BUTTON_LEFT) {
    if (press && y >= height - kTimelineHeightPx) {
      viewer.scrubbing = true;
      viewer.playing = false;
      viewer.SetFrame(TimelineFrame(viewer, x, width));
    } else {
      viewer.rotating = press;
      if (!press) viewer.scrubbing = false;
    }
  } else if (button == GLFW_MOUSE_BUTTON_RIGHT) {
    viewer.zooming = press;
  }
  viewer.dirty = true;
}

void OnCursor(GLFWwindow* window, double, double) {
  Viewer& viewer = *GetViewer(window);
  double x = 0.0, y = 0.0;
  CursorInFramebuffer(window, &x, &y);
  const double dx = x - viewer.last_x, dy = y - viewer.last_y;
  viewer.last_x = x;
  viewer.last_y = y;
  if (viewer.scrubbing) {
    int width = 1, height = 1;
    glfwGetFramebufferSize(window, &width, &height);
    viewer.SetFrame(TimelineFrame(viewer, x, width));
  } else if (viewer.rotating) {
    viewer.orbit.azimuth_deg -= 0.4 * dx;
    viewer.orbit.elevation_deg = std::clamp(viewer.orbit.elevation_deg + 0.4 * dy, -85.0, 85.0);
    viewer.dirty = true;
  } else if (viewer.zooming) {
    viewer.orbit.distance_m *= std::exp(0.005 * dy);
    viewer.dirty = true;
  }
}

void OnScroll(GLFWwindow* window, double, double yoffset) {
  Viewer& viewer = *GetViewer(window);
  viewer.orbit.distance_m *= std::exp(-0.1 * yoffset);
  viewer.dirty = true;
}

void OnResize(GLFWwindow* window, int, int) { GetViewer(window)->dirty = true; }

// The description of GLFW's last error on this thread, or "unknown error".
std::string GlfwError() {
  const char* description = nullptr;
  glfwGetError(&description);
  return description != nullptr ? description : "unknown error";
}

// Owns glfwInit/glfwTerminate and the window.
class Window {
 public:
  Window(int width, int height, bool visible) {
    const char* display = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    const std::string hint =
        " (no display? run it under a virtual X server: xvfb-run -a -s '-screen 0 1280x1024x24' confluent view ...)";
    if ((display == nullptr || *display == '\0') && (wayland == nullptr || *wayland == '\0'))
      throw Error("cannot open a window: DISPLAY is not set" + hint);
    if (glfwInit() != GLFW_TRUE) throw Error("cannot open a window: GLFW failed to initialise: " + GlfwError() + hint);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
    glfwWindowHint(GLFW_DOUBLEBUFFER, GLFW_TRUE);
    window_ = glfwCreateWindow(width, height, "confluent view", nullptr, nullptr);
    if (window_ == nullptr) {
      glfwTerminate();
      throw Error("cannot open a window with an OpenGL 3.3 core context: " + GlfwError() + hint);
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(1);
  }
  ~Window() {
    glfwDestroyWindow(window_);
    glfwTerminate();
  }
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
  GLFWwindow* get() const { return window_; }

 private:
  GLFWwindow* window_ = nullptr;
};

}  // namespace

void RunViewer(const ViewerRun& run, const ViewerOptions& options) {
  using namespace view_internal;
  const std::string& screenshot = options.screenshot;
  const int width = options.width, height = options.height;
  const int exit_after = options.exit_after_frames;
  RequireOption(exit_after >= 0, "ViewerOptions.exit_after_frames", exit_after, ">= 0");
  const double fps = options.fps > 0.0 ? options.fps : run.fps > 0.0 ? run.fps : kAssumedFrameRate;
  if (!(fps > 0.0 && fps <= 240.0)) throw UsageError("--fps: must be in (0, 240]");
  FrameCache frames(&run, 8);
  CaptureState capture = OpenCaptureFor(run);

  Viewer viewer;
  viewer.run = &run;
  viewer.frames = &frames;
  viewer.capture = &capture;
  viewer.fps = fps;
  viewer.show_frusta = options.show_frusta;
  viewer.playing = options.play;
  viewer.frame = run.first_frame;
  if (options.frame) {
    const int frame = *options.frame;
    if (frame < run.first_frame || frame > run.last_frame)
      throw UsageError("--frame: " + std::to_string(frame) + " is outside the run's frames " +
                       std::to_string(run.first_frame) + ".." + std::to_string(run.last_frame));
    viewer.frame = frame;
  }
  viewer.mode = !options.mode.empty() ? ParseMode(options.mode) : (capture.capture ? Mode::kTextured : Mode::kShaded);
  if (!screenshot.empty() && viewer.mode != Mode::kShaded && viewer.mode != Mode::kWireframe && !capture.capture)
    throw InputError(run.root, std::string(ModeName(viewer.mode)) + " needs the capture: " + capture.error);

  // The view stays fixed over the sequence: it frames the first frame that can be read.
  std::string error;
  std::shared_ptr<const Mesh> reference;
  for (int frame : run.present)
    if ((reference = frames.Get(frame, &error))) break;
  if (!reference) throw InputError(run.mesh_dir, "no frame can be read: " + error);
  viewer.orbit = InitialOrbit(*reference);
  viewer.orbit.azimuth_deg = options.azimuth_deg.value_or(viewer.orbit.azimuth_deg);
  viewer.orbit.elevation_deg = options.elevation_deg.value_or(viewer.orbit.elevation_deg);
  if (!(std::abs(viewer.orbit.elevation_deg) <= 85.0)) throw UsageError("--elevation: must be in -85..85 degrees");
  const double zoom = options.zoom;
  if (!(zoom > 0.0 && zoom < 1000.0)) throw UsageError("--zoom: must be positive");
  viewer.orbit.distance_m *= zoom;
  if (!screenshot.empty() && !run.has_frame(viewer.frame))
    throw InputError(run.FramePath(viewer.frame), "frame " + std::to_string(viewer.frame) + " is missing");

  Window window(width, height, true);
  viewer.window = window.get();
  glfwSetWindowUserPointer(viewer.window, &viewer);
  viewer.scene = std::make_unique<ViewerScene>();
  // The GL objects must go while the window's context is still current.
  struct SceneReset {
    Viewer* viewer;
    ~SceneReset() {
      glfwMakeContextCurrent(viewer->window);
      viewer->scene.reset();
      glfwMakeContextCurrent(nullptr);  // the offscreen renderers free their GL state in EGL
      viewer->texturer.reset();
      viewer->depth_renderer.reset();
      ReleaseCurrentEglContext();
    }
  } scene_reset{&viewer};

  if (!screenshot.empty()) {
    Draw(viewer, false);
    if (!viewer.frame_error.empty()) throw InputError(run.FramePath(viewer.frame), viewer.frame_error);
    if (!viewer.note.empty()) throw Error(viewer.note);
    SaveScreenshot(viewer, screenshot);
    std::printf("wrote %s (frame %d, %s)\n", screenshot.c_str(), viewer.frame, ModeName(viewer.mode));
    return;
  }

  glfwSetKeyCallback(viewer.window, OnKey);
  glfwSetMouseButtonCallback(viewer.window, OnMouseButton);
  glfwSetCursorPosCallback(viewer.window, OnCursor);
  glfwSetScrollCallback(viewer.window, OnScroll);
  glfwSetFramebufferSizeCallback(viewer.window, OnResize);
  std::printf(
      "confluent view: %s frames %d..%d (%s). Mouse: left drag orbit, right drag / wheel zoom, click the "
      "timeline to scrub.\nKeys: space play/pause, left/right step, T textured, S shaded, W wireframe, B blend "
      "weights, C camera frusta, P screenshot, Q quit.\n",
      run.mesh_kind.c_str(), run.first_frame, run.last_frame, run.mesh_dir.c_str());
  if (!capture.capture) std::printf("confluent view: %s\n", capture.error.c_str());
  double next_step = glfwGetTime() + 1.0 / viewer.fps;
  while (glfwWindowShouldClose(viewer.window) == GLFW_FALSE) {
    if (viewer.playing && glfwGetTime() >= next_step) {
      viewer.Step(1);
      next_step = glfwGetTime() + 1.0 / viewer.fps;
    }
    if (viewer.dirty) {
      viewer.dirty = false;
      Draw(viewer, true);
      UpdateTitle(viewer);
      glfwSwapBuffers(viewer.window);
      ++viewer.drawn_frames;
      if (exit_after > 0 && viewer.drawn_frames >= exit_after) break;
    }
    if (viewer.playing) {
      glfwWaitEventsTimeout(std::max(0.0, next_step - glfwGetTime()));
    } else if (exit_after > 0) {
      viewer.dirty = true;  // scripted smoke runs keep drawing
      glfwPollEvents();
    } else {
      glfwWaitEventsTimeout(0.5);
    }
  }
}

}  // namespace confluent
