#pragma once
// INTERNAL (render/projective_texture.cc and render/texture_*.cc only): ProjectiveTexturer's state
// and steps. Setup, the GL objects and the public methods are in projective_texture.cc; the input
// cameras' depth maps and SetFrame in texture_depth_maps.cc; the colour balance fit in
// texture_colour_balance.cc; Render on the CPU and with GL in texture_render.cc.

#include <epoxy/gl.h>

#include <Eigen/Core>
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <exception>
#include <future>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <thread>
#include <vector>

#include "render/cpu_raster.h"
#include "render/gl_program.h"
#include "render/projective_texture.h"
#include "render/texture_blend.h"
#include "render/texture_feather.h"
#include "render/texture_proxy.h"

namespace confluent {
namespace render_internal {

// Per-camera data kept on the CPU for the colour balance fit.
struct CameraFrame {
  Camera camera;
  Camera map_camera;  // the camera at the resolution of the depth and feather maps
  const float* depth_feather = nullptr;  // interleaved (camera z, feather) per map pixel, row-major
  const Image* image = nullptr;
  int visible_pixels = 0;

  float depth(int x, int y) const { return depth_feather[2 * (static_cast<std::size_t>(y) * map_camera.width + x)]; }
  float feather(int x, int y) const {
    return depth_feather[2 * (static_cast<std::size_t>(y) * map_camera.width + x) + 1];
  }
};

}  // namespace render_internal

using render_internal::BlendCamera;
using render_internal::BlendInput;
using render_internal::BlendPixel;
using render_internal::CamFromWorld;
using render_internal::CheckFaceIndices;
using render_internal::CheckVertices;
using render_internal::ClipFromCamera;
using render_internal::DepthFeatherMap;
using render_internal::FeatherScratch;
using render_internal::LinkProgram;
using render_internal::ProxyFaces;
using render_internal::Smoothstep;
using render_internal::kMaxCameras;
using render_internal::CameraFrame;

struct ProjectiveTexturer::Impl {
  ProjectiveTextureOptions options;
  MeshRendererOptions renderer_options;
  // Depth maps of input cameras with lens distortion (exact distortion); created on first use.
  std::unique_ptr<MeshRenderer> distortion_renderer;
  int mesh_handle = 0;
  Mesh mesh_topology;  // initial vertices and faces, for distortion_renderer
  EglContext context;
  int num_vertices = 0;
  int num_faces = 0;
  bool has_colors = false;

  GLuint gbuffer_program = 0, depth_program = 0;
  GLuint vertex_array = 0;
  // The depth maps draw the proxy's faces (or all faces) from the same vertex buffer.
  GLuint depth_vertex_array = 0, depth_index_buffer = 0;
  int num_depth_faces = 0;
  double proxy_bias_m = 0.0;  // added to depth_bias_m: how far the proxy can lie in front
  GLuint position_buffer = 0;
  GLuint color_buffer = 0;
  GLuint index_buffer = 0;
  // Render target of pass 1 of Render: the G-buffer.
  GLuint gbuffer_framebuffer = 0;
  GLuint gbuffer_textures[3] = {0, 0, 0};  // world point RGBA32F, normal RGBA16F, base colour RGBA8
  GLuint gbuffer_depth = 0;
  // The covered rectangle of the G-buffer read back: world point and normal (RGBA float), base
  // colour (RGBA8).
  std::vector<float> gbuffer_position, gbuffer_normal;
  std::vector<std::uint8_t> gbuffer_base;
  std::vector<Image> frame_images;  // per camera: the RGB8 image of the current frame
  std::vector<BlendCamera> blend_cameras;
  int fb_width = 0, fb_height = 0;
  // Render target of the input cameras' depth maps.
  // Render targets of the input cameras' depth maps, one per camera, so that all are drawn before
  // the first is read back (llvmpipe bins the next camera while it rasterises the previous one).
  struct DepthTarget {
    GLuint framebuffer = 0, depth = 0;
    int width = 0, height = 0;
  };
  std::vector<DepthTarget> depth_targets;
  RowMatrixX3f positions;  // the current frame's vertices in single precision
  // The CPU rasterisers (options.raster; null when GL draws): the depth maps' faces (proxy) and
  // all faces (the G-buffer); per worker thread, the projected vertices.
  bool cpu_raster = false;
  std::unique_ptr<CpuRasterizer> depth_rasterizer, view_rasterizer;
  std::vector<CpuRasterFrame> raster_frames;
  std::vector<PixelBox> feather_written;  // per camera: where the last feather map wrote
  std::vector<PixelBox> z_written;        // per camera: where camera_z may be nonzero
  std::vector<FeatherScratch> feather_scratch;  // per worker (CPU raster) or per camera (GL)
  // The novel view on the CPU: the mesh's faces and vertex colours (clamped to [0, 1]), and per
  // pixel 1 / z and the face drawn (-1 = none), nonzero only inside view_written.
  RowMatrixX3i mesh_faces;
  RowMatrixX3f vertex_colors;
  std::vector<float> view_inverse_depth;
  std::vector<std::int32_t> view_face_ids;
  PixelBox view_written;
  std::vector<std::uint8_t> readback;
  std::vector<std::vector<float>> camera_z;       // per camera: depth map read back
  std::vector<std::vector<float>> depth_feather;  // per camera: interleaved depth and feather
  std::vector<Image> scaled_masks;                // per camera: mask at the depth maps' resolution
  std::vector<Camera> vis_cameras;                // input cameras at the depth maps' resolution

  bool frame_set = false;
  std::vector<Camera> cameras;
  std::vector<Eigen::Vector3d> gains;       // colour balance of the frame (ones without)
  std::vector<Eigen::Vector3d> view_gains;  // SetViewGains: per camera, on top of `gains`
  TextureFrameInfo info;

  // Cached undistortion map of the last distorted view.
  struct ViewMap {
    Camera camera;
    cv::Mat map_x, map_y;  // output pixel -> ideal buffer position
    int x0 = 0, y0 = 0, width = 0, height = 0;
  };
  std::vector<ViewMap> view_maps;

  Impl(const Mesh& mesh, const ProjectiveTextureOptions& texture_options, const MeshRendererOptions& render_options);

  ~Impl();

  static void CheckGl(const std::string& step);

  // The checks of MeshRenderer::AddMesh that matter here: finite vertices, face indices in range,
  // colours.
  static void ValidateMesh(const Mesh& mesh);

  // Keeps the vertices in single precision and, when GL draws, uploads them.
  void UploadPositions(const RowMatrixX3d& vertices);

  // Draws the window depth of the mesh (current vertex buffer) in undistorted camera `i` into its
  // depth target; ReadDepth reads it back.
  void DrawDepth(int i, const Camera& camera);

  // Window depth drawn by DrawDepth(i, camera) into `out` (w x h, top row first; 1 where not
  // covered). WindowDepthToCameraZ converts it.
  void ReadDepth(int i, const Camera& camera, std::vector<float>* out);

  // Least-squares per-camera RGB gains from surface points seen well by several cameras.
  std::vector<Eigen::Vector3d> FitGains(const RowMatrixX3d& vertices, const std::vector<CameraFrame>& frames) const;

  void SetFrame(const RowMatrixX3d& vertices, const std::vector<Camera>& input_cameras, const std::vector<Image>& images,
                const std::vector<Image>& masks);

  void EnsureFramebuffer(int width, int height);

  // Pixels [x0, x1) x [y0, y1) of a width x height buffer (image rows = GL window rows here).
  struct PixelRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  };

  // The bounding box of the mesh's projected vertices (current frame) in a pinhole camera, plus a
  // pixel; the whole buffer when a vertex is not in front of the near plane.
  PixelRect CoveredRect(const Eigen::Matrix4d& cam_from_world, const Eigen::Matrix3d& K, int width, int height) const;

  // The undistortion map of a distorted view (cached per camera).
  const ViewMap& MapFor(const Camera& view);

  RenderResult Render(const Camera& view, bool want_silhouette);

  // The blending's view-dependent input.
  BlendInput MakeBlendInput(const Camera& view) const;

  // Calls row(y) for y in [0, rows) on all workers (this thread and the others), in bands of rows
  // interleaved over the workers so that each gets a share of the mesh.
  template <typename RowFunction>
  static void ForRowBands(int rows, const RowFunction& row) {
    constexpr int kBand = 8;
    const int workers = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, 8);
    auto run = [&](int worker) {
      for (int band = worker * kBand; band < rows; band += workers * kBand)
        for (int y = band; y < std::min(band + kBand, rows); ++y) row(y);
    };
    std::vector<std::future<void>> others;
    for (int worker = 1; worker < workers; ++worker) others.push_back(std::async(std::launch::async, run, worker));
    std::exception_ptr error;
    try {
      run(0);
    } catch (...) {
      error = std::current_exception();
    }
    for (std::future<void>& other : others) {
      try {
        other.get();
      } catch (...) {
        if (!error) error = std::current_exception();
      }
    }
    if (error) std::rethrow_exception(error);
  }

  // Render on the CPU into `readback` (ideal pinhole buffer `ideal`, RGBA8): the mesh rasterised
  // into face ids and 1 / z (two row halves on two threads), then per covered pixel the world point
  // from the pixel's ray, the face normal and the blending; the mesh's colour where no camera sees.
  void RenderCpu(const Camera& ideal, const PixelRect& rect);

  // Render with GL into `readback` (buffer width x height with intrinsics K, RGBA8): the mesh into
  // a G-buffer, read back, blended on the CPU.
  void RenderGl(const Camera& view, const Eigen::Matrix3d& K, int width, int height,
                const Eigen::Matrix4d& cam_from_world, const PixelRect& rect);

  // The output image of `view` from `readback` (width x height, RGBA8 premultiplied by coverage):
  // remapped through the distortion map when there is one, the background composited.
  RenderResult Composite(const Camera& view, int width, int height, const ViewMap* map, bool want_silhouette);

  // The input cameras as the blending sees them (after the frame's images, maps and gains).
  void SetBlendCameras();
};

}  // namespace confluent
