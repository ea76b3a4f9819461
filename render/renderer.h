#pragma once
// Offscreen rasterisation of triangle meshes into calibrated cameras (OpenGL through EGL):
// colour, depth, binary silhouette and triangle ids, pixel-exact with calib/camera.h.
//
// Projection. The GL projection is built from K so that the pixel (x, y) of the output image
// is the OpenCV pixel whose centre is at (x, y): the image spans [-0.5, W-0.5] x [-0.5, H-0.5].
// A pixel is covered when its centre is inside a projected triangle (GL's top-left rule).
// Rows come out top row first (OpenCV order); the y flip is folded into the projection.
//
// Lens distortion. Distorting vertices in the vertex shader bends only the corners of a
// triangle, not its edges, which is wrong for large triangles. Instead, a camera with
// distortion is rendered into an ideal pinhole buffer (same K, enlarged to cover the whole
// undistorted field of view) and then remapped on the GPU: each output (distorted) pixel looks
// up its ideal position Camera::UndistortPixel(x, y), precomputed once per camera. The pixel is
// covered when the bilinearly interpolated coverage of the 4 surrounding ideal samples is
// >= 0.5 (a sub-pixel outline, no nearest-neighbour jaggies); depth and triangle id come from
// the covered sample with the largest weight and colour from the covered samples, so the
// silhouette, depth, ids and colour stay mutually consistent.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "render/egl_context.h"

namespace confluent {

// A W x H buffer of 32-bit signed ids, row-major, top row first.
struct IdImage {
  int width = 0;
  int height = 0;
  std::vector<std::int32_t> ids;

  bool empty() const { return width == 0 || height == 0; }
  std::int32_t at(int x, int y) const { return ids[static_cast<std::size_t>(y) * width + x]; }
};

// Options fixed for the lifetime of a MeshRenderer.
struct MeshRendererOptions {
  EglContextOptions context;  // which EGL platform/device to use
  double near_m = 0.02;       // near clipping distance (camera z), metres
  double far_m = 1000.0;      // far clipping distance (camera z), metres
  // Largest ideal buffer used for distortion, relative to the image size per axis: strong
  // barrel distortion needs a larger undistorted field of view; beyond this it is cropped.
  double max_undistorted_scale = 2.0;
  // Resolution factor (1..4) of the ideal buffer for cameras with distortion (samples per ideal
  // pixel along each axis). With 1 an outline may move by up to half a pixel (mean blob centroid
  // error ~0.15 px); 3 makes it ~3x more accurate at ~9x the fragment cost. Odd factors put
  // pixel centres on samples; even ones have a slight outward bias.
  int distortion_supersampling = 1;
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// Lighting and colour encoding of the colour output.
struct ShadingOptions {
  // Lambert + ambient shading; false renders the raw albedo (unlit).
  bool lit = true;
  // Direction towards a distant light, world frame (normalised internally). World is Z up.
  Eigen::Vector3d light_direction_in_world = Eigen::Vector3d(0.3, -0.5, 1.0);
  // Light from the camera centre (a headlight) instead of light_direction_in_world.
  bool headlight = false;
  double ambient = 0.35;  // albedo factor independent of the normal
  double diffuse = 0.65;  // Lambert factor: albedo * diffuse * max(0, n . l)
  // Albedo of a mesh without vertex colours or texture: linear RGB in [0,1].
  Eigen::Vector3d default_albedo = Eigen::Vector3d(0.7, 0.7, 0.7);
  // Colour of pixels no mesh covers: linear RGB in [0,1].
  Eigen::Vector3d background = Eigen::Vector3d::Zero();
  // Encode the output with the sRGB transfer curve (true: ready to view/save; false: linear).
  bool srgb_output = true;
  // Pixel type of the colour image: kUInt8 or kFloat32 (values in [0,1]).
  PixelType color_type = PixelType::kUInt8;
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// What to render in one MeshRenderer::Render call.
struct RenderRequest {
  bool color = true;         // RGB colour image
  bool depth = false;        // float camera z (metres), 0 for background
  bool silhouette = false;   // uint8 mask, 255 where any drawn mesh covers the pixel, else 0
  bool triangle_id = false;  // int32 triangle id, -1 for background (see MeshRenderer::AddMesh)
  std::vector<int> meshes;   // handles of the meshes to draw; empty = all meshes
  // Skip faces seen from behind (faces are counter-clockwise seen from outside, core/mesh.h).
  // Same images for closed, consistently oriented meshes, and faster; wrong for open or
  // inconsistently oriented ones.
  bool cull_back_faces = false;
  ShadingOptions shading;
};

// The images of one render, each at the camera's resolution (top row first); an image that
// was not requested is empty.
struct RenderResult {
  Image color;       // W x H x 3, PixelType per ShadingOptions::color_type
  Image depth;       // W x H x 1 float32, camera z in metres; 0 where background
  Image silhouette;  // W x H x 1 uint8, 0 or 255
  IdImage triangle_id;  // face index (+ the mesh's id offset); -1 where background
};

// Renders meshes into calibrated cameras. Owns the EGL context, the framebuffers, the shader
// programs and the uploaded meshes, so that uploading once and then rendering many cameras and
// frames (updating only vertex positions) is fast. Not thread-safe; use from one thread.
class MeshRenderer {
 public:
  // Creates the GL context (throws RenderContextError when it cannot) and the shaders.
  explicit MeshRenderer(const MeshRendererOptions& options = {});
  ~MeshRenderer();
  MeshRenderer(const MeshRenderer&) = delete;
  MeshRenderer& operator=(const MeshRenderer&) = delete;

  // Uploads a mesh and returns its handle (0, 1, 2, ... in upload order). Albedo comes from
  // `texture` when the mesh has UVs and `texture` is not empty (8-bit or float, 1/3/4 channels;
  // linear RGB), else from the mesh's texture_path when it has UVs (read from disk), else from
  // the vertex colours, else ShadingOptions::default_albedo. Triangle ids of this mesh are its
  // face indices plus id_offset(handle) = the face count of all meshes uploaded before it (so a
  // single mesh gets plain face indices). `name` (e.g. the file path) names the mesh in errors.
  // Throws InputError when a vertex is NaN/infinite, a face index is out of range, the colours
  // or UVs are inconsistent or the texture cannot be read.
  int AddMesh(const Mesh& mesh, const std::string& name = "mesh", const Image& texture = {});

  // Replaces the vertex positions of mesh `handle` (same count, world frame, metres); normals
  // are recomputed. Throws InputError(name) for a wrong count or a non-finite vertex.
  void UpdateVertices(int handle, const RowMatrixX3d& vertices);

  // Number of meshes uploaded.
  int num_meshes() const;
  // First triangle id of mesh `handle` in the triangle-id image.
  int id_offset(int handle) const;

  // Renders the requested images of the chosen meshes into `camera` at its resolution, with
  // its lens distortion. Throws InputError when the camera fails Camera::Check (NaN, focal
  // <= 0, det(R) != +1, size <= 0) and UsageError for unknown handles or bad shading options.
  RenderResult Render(const Camera& camera, const RenderRequest& request = {});

  // The GL context's description (platform, vendor, renderer, version).
  const EglContextInfo& context_info() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace confluent
