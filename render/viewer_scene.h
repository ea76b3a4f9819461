#pragma once
// Drawing for the interactive viewer (`confluent view`): a mesh (lit vertex colours or a
// hidden-line wireframe), line sets (camera frusta), a full-window image (a projectively
// textured view rendered elsewhere) and flat 2D overlay rectangles (the timeline bar).
//
// Unlike MeshRenderer, ViewerScene owns no context: it draws with whatever OpenGL (>= 3.3
// core) context is current on the calling thread, typically a GLFW window's. The view is a
// calib/camera.h Camera (lens distortion ignored) and the GL projection is built from its K
// exactly as in render/renderer.h, so an image rendered offscreen into the same Camera lines
// up pixel for pixel with the geometry drawn here.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"

namespace confluent {

// How ViewerScene::DrawMesh draws the mesh.
enum class ViewerMeshStyle {
  kShaded,     // vertex colours (or default_albedo) lit by a headlight plus ambient
  kWireframe,  // edges only, hidden lines removed, in wire_color
  kFlat,       // vertex colours unlit (e.g. a colour code such as blend weights)
};

// Options of ViewerScene::DrawMesh.
struct ViewerMeshOptions {
  ViewerMeshStyle style = ViewerMeshStyle::kShaded;
  double ambient = 0.3;  // colour factor independent of the normal (kShaded)
  double diffuse = 0.7;  // headlight Lambert factor, two-sided: colour * diffuse * |n . l| (kShaded)
  // Colour of a mesh without vertex colours, RGB in [0,1].
  Eigen::Vector3d default_albedo = Eigen::Vector3d(0.75, 0.75, 0.75);
  Eigen::Vector3d wire_color = Eigen::Vector3d(0.9, 0.9, 0.9);  // kWireframe line colour, RGB in [0,1]
  double near_m = 0.02;   // near clipping distance (camera z), metres
  double far_m = 1000.0;  // far clipping distance (camera z), metres
};

// One coloured 3D line segment, world frame, metres.
struct ViewerLine {
  Eigen::Vector3d from_in_world;
  Eigen::Vector3d to_in_world;
  Eigen::Vector3d color;  // RGB in [0,1]
};

// An axis-aligned rectangle in window pixels (x right, y down from the top-left corner).
struct ViewerRect {
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
  Eigen::Vector4d color = Eigen::Vector4d(1.0, 1.0, 1.0, 1.0);  // RGBA in [0,1], alpha blended
};

// GPU state of the viewer: shaders, the uploaded mesh, lines and image. Requires a current
// OpenGL >= 3.3 core context for construction, every call and destruction; not thread-safe.
class ViewerScene {
 public:
  // Compiles the shaders. Throws RenderContextError when no suitable context is current.
  ViewerScene();
  ~ViewerScene();
  ViewerScene(const ViewerScene&) = delete;
  ViewerScene& operator=(const ViewerScene&) = delete;

  // Uploads a mesh (positions, area-weighted normals, colours). `colors` overrides the mesh's
  // vertex colours when it has one row per vertex (RGB in [0,1]). Throws InputError("mesh")
  // for face indices out of range or non-finite vertices.
  void SetMesh(const Mesh& mesh, const RowMatrixX3f& colors = {});
  // Replaces only the colours (one RGB row per vertex of the current mesh, or empty = the
  // mesh's own). Throws UsageError for a wrong row count.
  void SetMeshColors(const RowMatrixX3f& colors);
  bool has_mesh() const;

  // Replaces the line set.
  void SetLines(const std::vector<ViewerLine>& lines);
  // Replaces the full-window image (8-bit, 1/3/4 channels, top row first); empty = none.
  void SetImage(const Image& image);

  // Sets the viewport to width x height pixels and clears it to `background` (RGB in [0,1]).
  void Clear(int width_px, int height_px, const Eigen::Vector3d& background);
  // Draws the image stretched over the whole viewport (no depth).
  void DrawImage();
  // Draws the mesh seen from `view`; the viewport should have the view's aspect ratio.
  void DrawMesh(const Camera& view, const ViewerMeshOptions& options = {});
  // Draws the line set seen from `view`, depth-tested against what was drawn before.
  void DrawLines(const Camera& view, const ViewerMeshOptions& options = {});
  // Draws 2D rectangles on top of everything (viewport of width x height pixels).
  void DrawRects(const std::vector<ViewerRect>& rects, int width_px, int height_px);

  // Reads the current framebuffer (the back buffer of a window) as RGB8, top row first.
  Image ReadPixels(int width_px, int height_px) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Releases whatever EGL context is current on the calling thread (no-op when none). Needed
// before making a window system (GLX) context current on a thread that used an offscreen
// EGL renderer, since libglvnd allows one current context per thread across APIs.
void ReleaseCurrentEglContext();

}  // namespace confluent
