// Drawing `confluent view`'s window: the mesh shaded, as wireframe, projectively textured from
// the capture (offscreen, EGL) or coloured by its dominant blend camera; camera frusta and the
// timeline.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "pipeline/frame_range.h"
#include "viewer/view_state.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_ops.h"

namespace confluent::view_internal {
namespace {
namespace fs = std::filesystem;

// Lines of the capture cameras' frusta, each drawn to a fifth of the camera's distance to
// `target_in_world`: used cameras in their colour, excluded ones grey.
std::vector<ViewerLine> FrustumLines(const CaptureState& capture, const Eigen::Vector3d& target_in_world) {
  std::vector<ViewerLine> lines;
  if (!capture.capture) return lines;
  const Rig& rig = capture.capture->rig();
  for (int i = 0; i < rig.size(); ++i) {
    const Camera& camera = rig.cameras[i];
    const auto used = std::find(capture.used.begin(), capture.used.end(), i);
    const Eigen::Vector3d color = used == capture.used.end()
                                      ? Eigen::Vector3d(0.55, 0.55, 0.55)
                                      : CameraColor(static_cast<int>(used - capture.used.begin()));
    const Eigen::Vector3d center = camera.center_in_world();
    const double depth_m = std::max(0.05, 0.2 * (target_in_world - center).norm());
    const double w = camera.width - 0.5, h = camera.height - 0.5;
    const Eigen::Vector2d pixels[4] = {{-0.5, -0.5}, {w, -0.5}, {w, h}, {-0.5, h}};
    Eigen::Vector3d corners[4];
    for (int k = 0; k < 4; ++k) corners[k] = camera.Unproject(pixels[k], depth_m);
    for (int k = 0; k < 4; ++k) {
      lines.push_back({center, corners[k], color});
      lines.push_back({corners[k], corners[(k + 1) % 4], color});
    }
    // A tick on the top edge shows which way is up in the image.
    const Eigen::Vector3d top = camera.Unproject(Eigen::Vector2d(0.5 * w, -0.25 * h), depth_m);
    lines.push_back({corners[0] + 0.25 * (corners[1] - corners[0]), top, color});
    lines.push_back({corners[0] + 0.75 * (corners[1] - corners[0]), top, color});
  }
  return lines;
}

// Per-vertex colour of the input camera with the largest blend weight for `view`: among the
// cameras that see the vertex (depth test against a depth map, facing the camera, inside the
// image), the one whose ray is closest in angle to the view ray (Buehler et al. 2001). Dark grey
// where no camera sees the vertex. Needs the capture; throws on GL failures.
RowMatrixX3f DominantCameraColors(Viewer& viewer, const Camera& view) {
  const Mesh& mesh = *viewer.mesh;
  const CaptureState& capture = *viewer.capture;
  if (viewer.depth_frame != viewer.frame) {
    OffscreenScope offscreen(viewer.window);
    if (!viewer.depth_renderer) {
      viewer.depth_renderer = std::make_unique<MeshRenderer>();
      viewer.depth_renderer->AddMesh(mesh, viewer.run->FramePath(viewer.frame));
    } else {
      viewer.depth_renderer->UpdateVertices(0, mesh.vertices);
    }
    viewer.depth_cameras.clear();
    viewer.depth_maps.clear();
    RenderRequest request;
    request.color = false;
    request.depth = true;
    for (int index : capture.used) {
      const Camera& camera = capture.capture->rig().cameras[index];
      const double scale = std::min(1.0, 320.0 / std::max(camera.width, camera.height));
      viewer.depth_cameras.push_back(ScaledCamera(camera, scale));
      viewer.depth_maps.push_back(viewer.depth_renderer->Render(viewer.depth_cameras.back(), request).depth);
    }
    viewer.depth_frame = viewer.frame;
  }
  const RowMatrixX3d normals = VertexNormals(mesh);
  const Eigen::Vector3d view_center = view.center_in_world();
  RowMatrixX3f colors(mesh.num_vertices(), 3);
  constexpr double kDepthBias = 0.03;
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3d point = mesh.vertices.row(v).transpose();
    const Eigen::Vector3d to_view = (view_center - point).normalized();
    int best = -1;
    double best_angle = 1e9;
    for (std::size_t c = 0; c < viewer.depth_cameras.size(); ++c) {
      const Camera& camera = viewer.depth_cameras[c];
      const Eigen::Vector3d to_camera = (camera.center_in_world() - point).normalized();
      if (normals.row(v).dot(to_camera) <= 0.0) continue;
      Eigen::Vector2d pixel;
      if (!camera.ProjectChecked(point, &pixel)) continue;
      const int x = static_cast<int>(std::lround(pixel.x())), y = static_cast<int>(std::lround(pixel.y()));
      if (x < 0 || y < 0 || x >= camera.width || y >= camera.height) continue;
      const float depth = viewer.depth_maps[c].at<float>(x, y);
      if (depth <= 0.0f || camera.PointInCamera(point).z() > depth + kDepthBias) continue;
      const double angle = std::acos(std::clamp(to_view.dot(to_camera), -1.0, 1.0));
      if (angle < best_angle) {
        best_angle = angle;
        best = static_cast<int>(c);
      }
    }
    const Eigen::Vector3d color = best < 0 ? Eigen::Vector3d(0.2, 0.2, 0.2) : CameraColor(best);
    colors.row(v) = color.cast<float>().transpose();
  }
  return colors;
}

// Renders the textured view offscreen (ProjectiveTexturer) and returns it; empty on failure
// (viewer.texture_error says why).
Image TexturedView(Viewer& viewer, const Camera& view) {
  const CaptureState& capture = *viewer.capture;
  const Mesh& mesh = *viewer.mesh;
  OffscreenScope offscreen(viewer.window);
  try {
    if (!viewer.texturer || viewer.texturer_vertices != mesh.num_vertices()) {
      ProjectiveTextureOptions options;
      options.background = viewer.background;
      viewer.texturer = std::make_unique<ProjectiveTexturer>(mesh, options);
      viewer.texturer_vertices = mesh.num_vertices();
      viewer.texturer_frame = -1;
    }
    if (viewer.texturer_frame != viewer.frame) {
      if (viewer.frame >= capture.capture->num_frames())
        throw InputError(capture.capture->root(), "the capture has no frame " + std::to_string(viewer.frame));
      std::vector<Camera> cameras;
      std::vector<Image> images, masks;
      const fs::path run_masks = fs::path(viewer.run->root) / "masks";
      bool any_mask = false;
      for (int index : capture.used) {
        const Camera& camera = capture.capture->rig().cameras[index];
        cameras.push_back(camera);
        images.push_back(capture.capture->ReadFrame(index, viewer.frame));
        const fs::path mask_path = run_masks / camera.name / (FrameStem(viewer.frame) + ".png");
        Image mask;
        if (fs::exists(mask_path)) {
          mask = ReadMaskFile(mask_path.string());
        } else if (capture.capture->has_masks()) {
          mask = capture.capture->ReadMask(index, viewer.frame);
        }
        any_mask = any_mask || !mask.empty();
        masks.push_back(std::move(mask));
      }
      if (!any_mask) masks.clear();
      viewer.texturer->SetFrame(mesh.vertices, cameras, images, masks);
      viewer.texturer_frame = viewer.frame;
    }
    viewer.texture_error.clear();
    return viewer.texturer->Render(view).color;
  } catch (const std::exception& e) {
    viewer.texture_error = e.what();
    viewer.texturer_frame = -1;
    return {};
  }
}

}  // namespace

// Draws the current state into the window's back buffer.
void Draw(Viewer& viewer, bool with_timeline) {
  int width = 1, height = 1;
  glfwGetFramebufferSize(viewer.window, &width, &height);
  width = std::max(width, 1);
  height = std::max(height, 1);
  UpdateGeometry(viewer);
  const Camera view = viewer.orbit.View(width, height);
  ViewerMeshOptions options;
  options.near_m = std::max(0.005, 0.01 * viewer.orbit.distance_m);
  options.far_m = 100.0 * viewer.orbit.distance_m + 100.0;
  viewer.note.clear();

  Mode mode = viewer.mode;
  if ((mode == Mode::kTextured || mode == Mode::kWeights) && !viewer.capture->capture) {
    viewer.note = std::string(ModeName(mode)) + " needs the capture: " + viewer.capture->error;
    mode = Mode::kShaded;
  }
  Image textured;
  if (viewer.mesh && mode == Mode::kTextured) {
    textured = TexturedView(viewer, view);
    if (textured.empty()) {
      viewer.note = "texturing failed: " + viewer.texture_error;
      mode = Mode::kShaded;
    }
  }
  if (viewer.mesh && mode == Mode::kWeights) {
    try {
      RowMatrixX3f colors = DominantCameraColors(viewer, view);
      viewer.scene->SetMeshColors(colors);
      viewer.uploaded_weights = true;
    } catch (const std::exception& e) {
      viewer.note = std::string("blend weights failed: ") + e.what();
      mode = Mode::kShaded;
    }
  }
  if (mode != Mode::kWeights && viewer.uploaded_weights) {
    viewer.scene->SetMeshColors({});
    viewer.uploaded_weights = false;
  }

  viewer.scene->Clear(width, height, viewer.background);
  if (viewer.mesh) {
    if (mode == Mode::kTextured) {
      viewer.scene->SetImage(textured);
      viewer.scene->DrawImage();
    } else {
      options.style = mode == Mode::kWireframe ? ViewerMeshStyle::kWireframe
                      : mode == Mode::kWeights ? ViewerMeshStyle::kFlat
                                               : ViewerMeshStyle::kShaded;
      viewer.scene->DrawMesh(view, options);
    }
  }
  if (viewer.show_frusta && !viewer.frusta_uploaded) {
    viewer.scene->SetLines(FrustumLines(*viewer.capture, viewer.orbit.target));
    viewer.frusta_uploaded = true;
  }
  if (viewer.show_frusta) viewer.scene->DrawLines(view, options);
  if (with_timeline) {
    std::vector<ViewerRect> rects;
    const double y0 = height - kTimelineHeightPx, y1 = height;
    rects.push_back({0.0, y0, double(width), y1, Eigen::Vector4d(0.0, 0.0, 0.0, 0.6)});
    const int n = viewer.run->num_frames();
    const double slot = static_cast<double>(width) / n;
    const double played = (viewer.frame - viewer.run->first_frame + 1) * slot;
    rects.push_back({0.0, y0 + 8, played, y1 - 8, Eigen::Vector4d(0.3, 0.55, 0.9, 0.9)});
    for (int f = viewer.run->first_frame; f <= viewer.run->last_frame; ++f)
      if (!viewer.run->has_frame(f)) {
        const double x = (f - viewer.run->first_frame) * slot;
        rects.push_back({x, y0 + 4, x + std::max(1.0, slot), y1 - 4, Eigen::Vector4d(0.9, 0.2, 0.2, 0.9)});
      }
    const double cursor = (viewer.frame - viewer.run->first_frame + 0.5) * slot;
    rects.push_back({cursor - 2.0, y0 + 2, cursor + 2.0, y1 - 2, Eigen::Vector4d(1.0, 1.0, 1.0, 1.0)});
    viewer.scene->DrawRects(rects, width, height);
  }
}

}  // namespace confluent::view_internal
