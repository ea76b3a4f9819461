// ProjectiveTexturer: unstructured-lumigraph projective texturing; the mesh is rasterised (on the
// CPU or with GL), the blending runs on the CPU.
//
// SetFrame makes every input camera's depth map from a proxy of the mesh (vertex clustering at
// construction, on the mesh's own vertices, so it follows them), its feather map (distance to the
// mesh outline, to depth discontinuities and to the mask outline, exact up to the feather width)
// and a copy of its image, per camera on all cores. The depth maps come from the CPU rasteriser
// (render/cpu_raster.h) by default on a software GL: llvmpipe's per-triangle setup is
// single-threaded and its read-back costs as much again (8 cameras x 20K faces: ~70 ms there,
// ~10 ms of CPU here). With GL, all depth maps are drawn before the first read-back (llvmpipe bins
// one camera while it rasterises the previous) and each feather map is computed while the next
// map is read. Cameras with lens distortion always go through MeshRenderer (exact distortion).
// Render rasterises the mesh into face ids and 1 / z (CPU, two row halves in parallel) or into a
// GL G-buffer (world point, face normal, base colour, read back in the projected bounding box),
// and blends on the CPU (all cores): each covered pixel skips the cameras its surface faces away
// from, projects its world point into the others (distortion applied), tests visibility against
// the depth map (shadow-map style), keeps the best k cameras and samples only their images. A
// fragment shader on llvmpipe paid for every test of every camera on every pixel (execution masks,
// no real branches) and was 2-3 times slower.
//
// The feather maps are in render/texture_feather.cc, the proxy mesh in render/texture_proxy.cc,
// the per-pixel blending in render/texture_blend.cc.

#include "render/projective_texture.h"
#include "render/cpu_raster.h"
#include "render/gl_program.h"
#include "render/texture_blend.h"
#include "render/texture_feather.h"
#include "render/texture_proxy.h"

#include <epoxy/gl.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <future>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <unordered_map>
#include <unordered_set>
#include <thread>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "calib/capture.h"
#include "core/cv_interop.h"
#include "core/error.h"
#include "core/mesh_ops.h"

namespace confluent {
namespace {

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

// Pass 1 of Render: the mesh into a G-buffer (world point, face normal, base colour), with a cheap
// fragment shader, so that the cost of many tiny triangles does not multiply the blending cost.
constexpr const char* kVertexShader = R"(#version 430 core
layout(location = 0) in vec3 position_in_world;
layout(location = 1) in vec3 fallback_color;
uniform mat4 clip_from_world;
out vec3 v_position;
out vec3 v_color;
void main() {
  gl_Position = clip_from_world * vec4(position_in_world, 1.0);
  v_position = position_in_world;
  v_color = fallback_color;
}
)";

constexpr const char* kGBufferFragmentShader = R"(#version 430 core
in vec3 v_position;
in vec3 v_color;
layout(location = 0) out vec4 out_position;  // w = 1 where the mesh covers the pixel
layout(location = 1) out vec4 out_normal;    // face normal, towards the view
layout(location = 2) out vec4 out_base;      // colour where no camera sees the point
uniform vec3 view_center;
uniform int use_vertex_colors;
uniform vec3 fallback;
void main() {
  vec3 X = v_position;
  vec3 to_view = view_center - X;
  to_view /= max(length(to_view), 1e-6);
  vec3 n = cross(dFdx(X), dFdy(X));
  float n_length = length(n);
  n = n_length > 0.0 ? n / n_length : to_view;
  if (dot(n, to_view) < 0.0) n = -n;
  out_position = vec4(X, 1.0);
  out_normal = vec4(n, 0.0);
  out_base = vec4(use_vertex_colors != 0 ? v_color : fallback, 1.0);
}
)";


// Depth maps of the input cameras (SetFrame): depth buffer only (no colour, no varyings, the
// cheapest pass llvmpipe has); camera z is recovered from the window depth on the CPU.
constexpr const char* kDepthVertexShader = R"(#version 430 core
layout(location = 0) in vec3 position_in_world;
uniform mat4 clip_from_world;
void main() { gl_Position = clip_from_world * vec4(position_in_world, 1.0); }
)";

constexpr const char* kDepthFragmentShader = R"(#version 430 core
void main() {}
)";

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

// The camera with its image resized by `scale` (at least 1 pixel).
Camera Scaled(const Camera& camera, double scale) {
  if (scale == 1.0) return camera;
  return ResizedCamera(camera, std::max(1, static_cast<int>(std::lround(camera.width * scale))),
                       std::max(1, static_cast<int>(std::lround(camera.height * scale))));
}

// `mask` at width x height (itself when the size matches or it is empty; else an area-averaged
// copy in `storage`, thresholded at half coverage).
const Image& ScaledMask(const Image& mask, int width, int height, Image* storage) {
  if (mask.empty() || (mask.width == width && mask.height == height)) return mask;
  cv::Mat resized;
  cv::resize(AsCvMat(mask), resized, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  cv::threshold(resized, resized, 127, 255, cv::THRESH_BINARY);
  *storage = ImageFromCvMat(resized);
  return *storage;
}

// Bilinear RGB sample of an RGB8 image at a pixel position (centres at integers), in [0,1].
Eigen::Vector3d SampleRgb(const Image& image, const Eigen::Vector2d& pixel) {
  const double x = std::clamp(pixel.x(), 0.0, image.width - 1.0), y = std::clamp(pixel.y(), 0.0, image.height - 1.0);
  const int x0 = std::min(static_cast<int>(x), image.width - 2 < 0 ? 0 : image.width - 2);
  const int y0 = std::min(static_cast<int>(y), image.height - 2 < 0 ? 0 : image.height - 2);
  const int x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
  const double fx = x - x0, fy = y - y0;
  Eigen::Vector3d value;
  for (int c = 0; c < 3; ++c) {
    const double top = (1 - fx) * image.at<std::uint8_t>(x0, y0, c) + fx * image.at<std::uint8_t>(x1, y0, c);
    const double bottom = (1 - fx) * image.at<std::uint8_t>(x0, y1, c) + fx * image.at<std::uint8_t>(x1, y1, c);
    value[c] = ((1 - fy) * top + fy * bottom) / 255.0;
  }
  return value;
}

// Window depth (GL depth buffer in [0, 1] of ClipFromCamera's projection) -> camera z, in place;
// the cleared value 1 (nothing drawn) -> 0.
void WindowDepthToCameraZ(double near_m, double far_m, std::vector<float>* depth) {
  const double a = (far_m + near_m) / (far_m - near_m), b = -2.0 * far_m * near_m / (far_m - near_m);
  for (float& d : *depth) d = d >= 1.0f ? 0.0f : static_cast<float>(b / ((2.0 * d - 1.0) - a));
}

// Asks for transparent huge pages on a large buffer not yet touched (Linux; a hint, ignored
// elsewhere): the blending reads the depth maps and images of 8 cameras (~70 MB) at scattered
// places, and with 4 KB pages it waits on TLB misses.
void AdviseHugePages(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t kHuge = 2u << 20;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(data) + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(kHuge - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

// Empties `buffer` and reserves `count` elements in a fresh allocation advised for huge pages.
template <typename T>
void ReserveWithHugePages(std::size_t count, std::vector<T>* buffer) {
  std::vector<T>().swap(*buffer);
  buffer->reserve(count);
  AdviseHugePages(buffer->data(), count * sizeof(T));
}

}  // namespace

void ProjectiveTextureOptions::Check() const {
  if (best_k < 1 || best_k > 8)
    throw UsageError("projective texture best_k must be in 1..8, got " + std::to_string(best_k));
  if (!(depth_bias_m >= 0.0) || !std::isfinite(depth_bias_m)) throw UsageError("depth_bias_m must be >= 0");
  if (!(feather_px >= 0.0) || !std::isfinite(feather_px)) throw UsageError("feather_px must be >= 0");
  if (!(depth_edge_m > 0.0) || !std::isfinite(depth_edge_m)) throw UsageError("depth_edge_m must be > 0");
  if (!(resolution_weight >= 0.0) || !std::isfinite(resolution_weight))
    throw UsageError("resolution_weight must be >= 0");
  if (!(grazing_cos >= 0.0 && grazing_cos <= 1.0)) throw UsageError("grazing_cos must be in [0, 1]");
  if (!(visibility_scale > 0.0 && visibility_scale <= 1.0))
    throw UsageError("visibility_scale must be in (0, 1], got " + std::to_string(visibility_scale));
  if (visibility_faces < 0) throw UsageError("visibility_faces must be >= 0, got " + std::to_string(visibility_faces));
  if (colour_balance_samples < 1) throw UsageError("colour_balance_samples must be >= 1");
  if (!fallback_color.allFinite() || !background.allFinite()) throw UsageError("colours must be finite");
}

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

  Impl(const Mesh& mesh, const ProjectiveTextureOptions& texture_options, const MeshRendererOptions& render_options)
      : options(texture_options), renderer_options(render_options), context(render_options.context) {
    ValidateMesh(mesh);
    mesh_topology.vertices = mesh.vertices;
    mesh_topology.faces = mesh.faces;
    num_vertices = mesh.num_vertices();
    num_faces = mesh.num_faces();
    has_colors = mesh.has_colors();
    mesh_faces = mesh.faces;
    if (has_colors) vertex_colors = mesh.colors.cast<float>().cwiseMax(0.0f).cwiseMin(1.0f);
    context.MakeCurrent();
    gbuffer_program = LinkProgram(kVertexShader, kGBufferFragmentShader, "projective texture (G-buffer)");
    depth_program = LinkProgram(kDepthVertexShader, kDepthFragmentShader, "projective texture (depth maps)");
    glGenVertexArrays(1, &vertex_array);
    glBindVertexArray(vertex_array);
    glGenBuffers(1, &position_buffer);
    glGenBuffers(1, &color_buffer);
    glGenBuffers(1, &index_buffer);
    glBindBuffer(GL_ARRAY_BUFFER, position_buffer);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(num_vertices) * 3 * sizeof(float), nullptr, GL_DYNAMIC_DRAW);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    if (has_colors) {
      std::vector<float> colors(static_cast<std::size_t>(num_vertices) * 3);
      for (int v = 0; v < num_vertices; ++v)
        for (int k = 0; k < 3; ++k) colors[3 * v + k] = std::clamp(mesh.colors(v, k), 0.0f, 1.0f);
      glBindBuffer(GL_ARRAY_BUFFER, color_buffer);
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(colors.size() * sizeof(float)), colors.data(),
                   GL_STATIC_DRAW);
      glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
      glEnableVertexAttribArray(1);
    }
    std::vector<std::uint32_t> indices(static_cast<std::size_t>(num_faces) * 3);
    for (int f = 0; f < num_faces; ++f)
      for (int k = 0; k < 3; ++k) indices[3 * f + k] = static_cast<std::uint32_t>(mesh.faces(f, k));
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
                 indices.data(), GL_STATIC_DRAW);
    // The depth maps' proxy: the same vertex buffer, its own faces.
    const int proxy_target = options.visibility_faces;
    num_depth_faces = num_faces;
    glGenVertexArrays(1, &depth_vertex_array);
    glBindVertexArray(depth_vertex_array);
    glBindBuffer(GL_ARRAY_BUFFER, position_buffer);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    glGenBuffers(1, &depth_index_buffer);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, depth_index_buffer);
    if (proxy_target > 0 && num_faces > proxy_target * 3 / 2) {
      double deviation_m = 0.0;
      RowMatrixX3i proxy = ProxyFaces(mesh, proxy_target, &deviation_m);
      if (proxy.rows() > 0) {  // else (a degenerate mesh) the full mesh
        mesh_topology.faces = std::move(proxy);
        proxy_bias_m = deviation_m;
        num_depth_faces = mesh_topology.num_faces();
        indices.resize(static_cast<std::size_t>(num_depth_faces) * 3);
        for (int f = 0; f < num_depth_faces; ++f)
          for (int k = 0; k < 3; ++k) indices[3 * f + k] = static_cast<std::uint32_t>(mesh_topology.faces(f, k));
      }
    }
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
                 indices.data(), GL_STATIC_DRAW);
    glBindVertexArray(0);
    cpu_raster = options.raster == ProjectiveTextureOptions::Raster::kCpu ||
                 (options.raster == ProjectiveTextureOptions::Raster::kAuto && context.info().software);
    if (cpu_raster) {
      CpuRasterOptions raster;
      raster.near_m = renderer_options.near_m;
      raster.far_m = renderer_options.far_m;
      raster.cull_back_faces = options.cull_back_faces;
      depth_rasterizer = std::make_unique<CpuRasterizer>(mesh_topology.faces, num_vertices, raster);
      view_rasterizer = std::make_unique<CpuRasterizer>(mesh.faces, num_vertices, raster);
    }
    UploadPositions(mesh.vertices);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    CheckGl("setup");
  }

  ~Impl() {
    try {
      context.MakeCurrent();
    } catch (...) {
      return;
    }
    glDeleteProgram(gbuffer_program);
    glDeleteProgram(depth_program);
    const GLuint buffers[] = {position_buffer, color_buffer, index_buffer, depth_index_buffer};
    glDeleteBuffers(4, buffers);
    const GLuint arrays[] = {vertex_array, depth_vertex_array};
    glDeleteVertexArrays(2, arrays);
    glDeleteTextures(3, gbuffer_textures);
    glDeleteFramebuffers(1, &gbuffer_framebuffer);
    glDeleteRenderbuffers(1, &gbuffer_depth);
    for (const DepthTarget& target : depth_targets) {
      glDeleteFramebuffers(1, &target.framebuffer);
      glDeleteRenderbuffers(1, &target.depth);
    }
  }

  static void CheckGl(const std::string& step) {
    const GLenum error = glGetError();
    if (error != GL_NO_ERROR) {
      std::ostringstream out;
      out << "OpenGL: projective texturing " << step << " failed (GL error 0x" << std::hex << error << ")";
      throw RenderContextError(out.str());
    }
  }

  // The checks of MeshRenderer::AddMesh that matter here: finite vertices, face indices in range,
  // colours.
  static void ValidateMesh(const Mesh& mesh) {
    CheckVertices(mesh.vertices, "mesh");
    CheckFaceIndices(mesh, "mesh");
    const int n = mesh.num_vertices();
    if (mesh.colors.rows() != 0 && mesh.colors.rows() != n)
      throw InputError("mesh", "has " + std::to_string(mesh.colors.rows()) + " vertex colours for " +
                                   std::to_string(n) + " vertices");
    if (mesh.has_colors() && !mesh.colors.allFinite()) throw InputError("mesh", "vertex colours contain NaN");
  }

  // Keeps the vertices in single precision and, when GL draws, uploads them.
  void UploadPositions(const RowMatrixX3d& vertices) {
    positions = vertices.cast<float>();
    if (cpu_raster) return;
    glBindBuffer(GL_ARRAY_BUFFER, position_buffer);
    glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(positions.size() * sizeof(float)), positions.data());
  }

  // Draws the window depth of the mesh (current vertex buffer) in undistorted camera `i` into its
  // depth target; ReadDepth reads it back.
  void DrawDepth(int i, const Camera& camera) {
    const int w = camera.width, h = camera.height;
    if (static_cast<int>(depth_targets.size()) <= i) depth_targets.resize(i + 1);
    DepthTarget& target = depth_targets[i];
    if (target.framebuffer == 0) {
      glGenFramebuffers(1, &target.framebuffer);
      glGenRenderbuffers(1, &target.depth);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, target.framebuffer);
    if (target.width != w || target.height != h) {
      glBindRenderbuffer(GL_RENDERBUFFER, target.depth);
      glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, target.depth);
      glDrawBuffer(GL_NONE);
      glReadBuffer(GL_NONE);
      if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw RenderContextError("OpenGL: projective texture depth framebuffer " + std::to_string(w) + "x" +
                                 std::to_string(h) + " is incomplete");
      target.width = w;
      target.height = h;
    }
    glViewport(0, 0, w, h);
    const GLfloat far_depth = 1.0f;
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
    render_internal::SetMeshRasterState(options.cull_back_faces, GL_LESS);
    const Eigen::Matrix4f clip_from_world =
        (ClipFromCamera(camera.K, w, h, renderer_options.near_m, renderer_options.far_m) * CamFromWorld(camera))
            .cast<float>();
    glUseProgram(depth_program);
    glUniformMatrix4fv(glGetUniformLocation(depth_program, "clip_from_world"), 1, GL_FALSE, clip_from_world.data());
    glBindVertexArray(depth_vertex_array);
    glDrawElements(GL_TRIANGLES, num_depth_faces * 3, GL_UNSIGNED_INT, nullptr);
    glBindVertexArray(0);
    glDisable(GL_CULL_FACE);
    CheckGl("depth map of camera " + camera.name);
  }

  // Window depth drawn by DrawDepth(i, camera) into `out` (w x h, top row first; 1 where not
  // covered). WindowDepthToCameraZ converts it.
  void ReadDepth(int i, const Camera& camera, std::vector<float>* out) {
    out->resize(static_cast<std::size_t>(camera.width) * camera.height);
    glBindFramebuffer(GL_FRAMEBUFFER, depth_targets[i].framebuffer);
    glReadPixels(0, 0, camera.width, camera.height, GL_DEPTH_COMPONENT, GL_FLOAT, out->data());
    CheckGl("reading the depth map of camera " + camera.name);
  }

  // Least-squares per-camera RGB gains from surface points seen well by several cameras.
  std::vector<Eigen::Vector3d> FitGains(const RowMatrixX3d& vertices, const std::vector<CameraFrame>& frames) const {
    const int n = static_cast<int>(frames.size());
    std::vector<Eigen::Vector3d> result(n, Eigen::Vector3d::Ones());
    if (n < 2) return result;
    const int stride = std::max(1, num_vertices / options.colour_balance_samples);
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
    int equations = 0;
    std::vector<int> seen;
    std::vector<Eigen::Vector3d> logs;
    for (int v = 0; v < num_vertices; v += stride) {
      const Eigen::Vector3d X = vertices.row(v).transpose();
      seen.clear();
      logs.clear();
      for (int i = 0; i < n; ++i) {
        const CameraFrame& frame = frames[i];
        Eigen::Vector2d pixel;
        if (!frame.camera.ProjectChecked(X, &pixel)) continue;
        const int px = static_cast<int>(std::lround(pixel.x())), py = static_cast<int>(std::lround(pixel.y()));
        if (px < 0 || py < 0 || px >= frame.camera.width || py >= frame.camera.height) continue;
        // The same pixel in the depth and feather maps (texel centres at +0.5).
        const Camera& map = frame.map_camera;
        const int mx = std::min(map.width - 1, static_cast<int>((px + 0.5) * map.width / frame.camera.width));
        const int my = std::min(map.height - 1, static_cast<int>((py + 0.5) * map.height / frame.camera.height));
        const float depth = frame.depth(mx, my);
        if (depth <= 0.0f || frame.camera.PointInCamera(X).z() > depth + options.depth_bias_m + proxy_bias_m)
          continue;
        if (frame.feather(mx, my) < 0.99f) continue;
        const Eigen::Vector3d rgb = SampleRgb(*frame.image, pixel);
        if (rgb.minCoeff() < 0.03 || rgb.maxCoeff() > 0.97) continue;  // log of clipped values is unreliable
        seen.push_back(i);
        logs.push_back(rgb.array().log().matrix());
      }
      // Pairwise equations: log g_a - log g_b = log c_b - log c_a.
      for (std::size_t a = 0; a < seen.size(); ++a)
        for (std::size_t b = a + 1; b < seen.size(); ++b) {
          const int i = seen[a], j = seen[b];
          normal(i, i) += 1;
          normal(j, j) += 1;
          normal(i, j) -= 1;
          normal(j, i) -= 1;
          const Eigen::Vector3d d = logs[b] - logs[a];
          rhs.row(i) += d.transpose();
          rhs.row(j) -= d.transpose();
          ++equations;
        }
    }
    if (equations == 0) return result;
    // Weak prior towards gain 1 keeps cameras without overlaps (and the global scale) fixed.
    normal += 1e-3 * equations / n * Eigen::MatrixXd::Identity(n, n);
    const Eigen::MatrixXd log_gains = normal.ldlt().solve(rhs);
    for (int i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) result[i][c] = std::clamp(std::exp(log_gains(i, c)), 0.5, 2.0);
    return result;
  }

  void SetFrame(const RowMatrixX3d& vertices, const std::vector<Camera>& input_cameras, const std::vector<Image>& images,
                const std::vector<Image>& masks) {
    frame_set = false;
    const int n = static_cast<int>(input_cameras.size());
    if (static_cast<int>(images.size()) != n)
      throw UsageError("ProjectiveTexturer::SetFrame: " + std::to_string(images.size()) + " images for " +
                       std::to_string(n) + " cameras");
    if (!masks.empty() && static_cast<int>(masks.size()) != n)
      throw UsageError("ProjectiveTexturer::SetFrame: " + std::to_string(masks.size()) + " masks for " +
                       std::to_string(n) + " cameras");
    if (n > kMaxCameras)
      throw UsageError("projective texturing supports at most " + std::to_string(kMaxCameras) + " cameras, got " +
                       std::to_string(n));
    if (vertices.rows() != num_vertices)
      throw InputError("mesh", "got " + std::to_string(vertices.rows()) + " vertices for a mesh with " +
                                   std::to_string(num_vertices));
    std::vector<Image> converted(n);  // only for images that are not RGB8 already
    std::vector<const Image*> rgb(n);
    for (int i = 0; i < n; ++i) {
      const Camera& camera = input_cameras[i];
      camera.Check("projective texture");
      if (images[i].width != camera.width || images[i].height != camera.height)
        throw InputError("camera " + camera.name, "image is " + std::to_string(images[i].width) + "x" +
                                                      std::to_string(images[i].height) + ", calibration says " +
                                                      std::to_string(camera.width) + "x" + std::to_string(camera.height));
      if (!masks.empty() && !masks[i].empty() &&
          (masks[i].width != camera.width || masks[i].height != camera.height || masks[i].channels != 1 ||
           masks[i].type != PixelType::kUInt8))
        throw InputError("camera " + camera.name, "mask must be a 1-channel 8-bit image of the camera's size");
      if (images[i].channels == 3 && images[i].type == PixelType::kUInt8) {
        rgb[i] = &images[i];
      } else {
        converted[i] = ToRgb8(images[i]);
        rgb[i] = &converted[i];
      }
    }
    CheckVertices(vertices, "mesh");
    context.MakeCurrent();
    UploadPositions(vertices);

    // Per camera: the depth map (GL or the CPU rasteriser), the feather map and the copy of the
    // image the blending reads.
    camera_z.resize(std::max<std::size_t>(camera_z.size(), n));
    depth_feather.resize(std::max<std::size_t>(depth_feather.size(), n));
    feather_written.resize(std::max<std::size_t>(feather_written.size(), n));
    z_written.resize(std::max<std::size_t>(z_written.size(), n));
    vis_cameras.clear();
    for (const Camera& camera : input_cameras) vis_cameras.push_back(Scaled(camera, options.visibility_scale));
    const double feather_px = options.feather_px * options.visibility_scale;
    static const Image kNoMask;
    scaled_masks.resize(n);
    frame_images.resize(n);
    std::vector<int> visible(n, 0);
    // How camera_z[i] was filled: 0 = to be drawn by the CPU rasteriser, 1 = GL window depth,
    // 2 = camera z (distorted cameras, MeshRenderer).
    std::vector<int> source(n, 0);
    auto process = [&](int i, CpuRasterFrame* raster_frame, FeatherScratch* scratch) {
      const Camera& camera = vis_cameras[i];
      const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
      PixelBox z_box{0, 0, camera.width, camera.height};
      if (source[i] == 0) {
        // CPU: clears only what the last frame drew.
        z_box = depth_rasterizer->DrawDepth(camera, positions, raster_frame, &camera_z[i], &z_written[i]);
      } else if (source[i] == 1) {
        WindowDepthToCameraZ(renderer_options.near_m, renderer_options.far_m, &camera_z[i]);
      }
      z_written[i] = z_box;
      if (depth_feather[i].size() != 2 * pixels) {
        ReserveWithHugePages(2 * pixels, &depth_feather[i]);
        depth_feather[i].assign(2 * pixels, 0.0f);
        feather_written[i] = PixelBox();
      }
      const Image& mask = masks.empty() ? kNoMask : masks[i];
      const Image& map_mask = ScaledMask(mask, camera.width, camera.height, &scaled_masks[i]);
      visible[i] = DepthFeatherMap(camera_z[i].data(), camera.width, camera.height, z_box, map_mask, options,
                                   feather_px, depth_feather[i].data(), &feather_written[i], scratch);
      // The blending reads the images on the CPU: keep them (the caller's may go away).
      if (frame_images[i].data.capacity() < rgb[i]->data.size())
        ReserveWithHugePages(rgb[i]->data.size(), &frame_images[i].data);
      if (rgb[i] == &converted[i]) frame_images[i] = std::move(converted[i]);
      else frame_images[i] = *rgb[i];
    };
    // Cameras with lens distortion: MeshRenderer (exact distortion), on this thread (GL).
    bool distortion_vertices_set = false;
    auto render_distorted = [&](int i) {
      if (!distortion_renderer) {
        distortion_renderer = std::make_unique<MeshRenderer>(renderer_options);
        mesh_handle = distortion_renderer->AddMesh(mesh_topology, "mesh");
      }
      if (!distortion_vertices_set) distortion_renderer->UpdateVertices(mesh_handle, vertices);
      distortion_vertices_set = true;
      RenderRequest request;
      request.color = false;
      request.depth = true;
      request.cull_back_faces = options.cull_back_faces;
      const Image depth = distortion_renderer->Render(vis_cameras[i], request).depth;
      camera_z[i].assign(depth.ptr<float>(), depth.ptr<float>() + depth.data.size() / sizeof(float));
      source[i] = 2;
      context.MakeCurrent();
    };
    // Declared before the jobs: the workers use it until the jobs are joined below.
    std::atomic<int> next{0};
    std::vector<std::future<void>> jobs;
    try {
      if (cpu_raster) {
        // Distorted cameras first (GL, this thread), then every camera's maps on all workers.
        for (int i = 0; i < n; ++i)
          if (vis_cameras[i].has_distortion()) render_distorted(i);
        const int workers = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, std::min(n, 8));
        raster_frames.resize(std::max<std::size_t>(raster_frames.size(), std::max(workers, 1)));
        feather_scratch.resize(std::max<std::size_t>(feather_scratch.size(), std::max(workers, 1)));
        auto work = [&](int worker) {
          for (int i = next++; i < n; i = next++) process(i, &raster_frames[worker], &feather_scratch[worker]);
        };
        for (int worker = 1; worker < workers; ++worker) jobs.push_back(std::async(std::launch::async, work, worker));
        work(0);
      } else {
        // GL: all undistorted depth maps are drawn before the first read-back (llvmpipe bins one
        // camera while it rasterises the previous); each camera's feather map is computed on a
        // worker thread while the next map is read.
        for (int i = 0; i < n; ++i)
          if (!vis_cameras[i].has_distortion()) DrawDepth(i, vis_cameras[i]);
        feather_scratch.resize(std::max<std::size_t>(feather_scratch.size(), n));
        for (int i = 0; i < n; ++i) {
          if (vis_cameras[i].has_distortion()) {
            render_distorted(i);
          } else {
            ReadDepth(i, vis_cameras[i], &camera_z[i]);
            source[i] = 1;
          }
          jobs.push_back(std::async(std::launch::async, process, i, nullptr, &feather_scratch[i]));
        }
      }
      for (std::future<void>& job : jobs) job.get();
    } catch (...) {
      for (std::future<void>& job : jobs)
        if (job.valid()) job.wait();
      throw;
    }
    std::vector<CameraFrame> frames(n);
    info = TextureFrameInfo();
    for (int i = 0; i < n; ++i) {
      frames[i].camera = input_cameras[i];
      frames[i].map_camera = vis_cameras[i];
      frames[i].depth_feather = depth_feather[i].data();
      frames[i].image = &frame_images[i];
      frames[i].visible_pixels = visible[i];
      info.visible_pixels.push_back(visible[i]);
    }
    gains = options.colour_balance ? FitGains(vertices, frames) : std::vector<Eigen::Vector3d>(n, Eigen::Vector3d::Ones());
    info.colour_gains = gains;
    cameras = input_cameras;
    if (view_gains.size() != cameras.size()) view_gains.clear();
    SetBlendCameras();
    frame_set = true;
  }

  void EnsureFramebuffer(int width, int height) {
    if (gbuffer_framebuffer != 0 && width == fb_width && height == fb_height) return;
    if (gbuffer_framebuffer == 0) {
      glGenFramebuffers(1, &gbuffer_framebuffer);
      glGenRenderbuffers(1, &gbuffer_depth);
    }
    const GLuint old[] = {gbuffer_textures[0], gbuffer_textures[1], gbuffer_textures[2]};
    glDeleteTextures(3, old);
    glGenTextures(3, gbuffer_textures);
    const GLenum formats[3] = {GL_RGBA32F, GL_RGBA16F, GL_RGBA8};
    glBindFramebuffer(GL_FRAMEBUFFER, gbuffer_framebuffer);
    for (int k = 0; k < 3; ++k) {
      glBindTexture(GL_TEXTURE_2D, gbuffer_textures[k]);
      glTexStorage2D(GL_TEXTURE_2D, 1, formats[k], width, height);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + k, GL_TEXTURE_2D, gbuffer_textures[k], 0);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, gbuffer_depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, gbuffer_depth);
    const GLenum draw_buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, draw_buffers);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw RenderContextError("OpenGL: projective texture framebuffer " + std::to_string(width) + "x" +
                               std::to_string(height) + " is incomplete");
    fb_width = width;
    fb_height = height;
  }

  // Pixels [x0, x1) x [y0, y1) of a width x height buffer (image rows = GL window rows here).
  struct PixelRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  };

  // The bounding box of the mesh's projected vertices (current frame) in a pinhole camera, plus a
  // pixel; the whole buffer when a vertex is not in front of the near plane.
  PixelRect CoveredRect(const Eigen::Matrix4d& cam_from_world, const Eigen::Matrix3d& K, int width, int height) const {
    const Eigen::Matrix<double, 3, 4> pixel_from_world = K * cam_from_world.topRows<3>();
    double min_x = 1e30, min_y = 1e30, max_x = -1e30, max_y = -1e30;
    for (int v = 0; v < num_vertices; ++v) {
      const Eigen::Vector3d X = positions.row(v).transpose().cast<double>();
      const Eigen::Vector3d p = pixel_from_world * X.homogeneous();
      if (!(p.z() > renderer_options.near_m)) return PixelRect{0, 0, width, height};
      const double x = p.x() / p.z(), y = p.y() / p.z();
      min_x = std::min(min_x, x);
      max_x = std::max(max_x, x);
      min_y = std::min(min_y, y);
      max_y = std::max(max_y, y);
    }
    PixelRect rect;
    if (num_vertices == 0 || max_x < -1.0 || max_y < -1.0 || min_x > width || min_y > height) return rect;
    rect.x0 = std::max(0, static_cast<int>(std::floor(std::max(min_x, -1.0))) - 1);
    rect.y0 = std::max(0, static_cast<int>(std::floor(std::max(min_y, -1.0))) - 1);
    rect.x1 = std::min(width, static_cast<int>(std::ceil(std::min(max_x, width + 1.0))) + 2);
    rect.y1 = std::min(height, static_cast<int>(std::ceil(std::min(max_y, height + 1.0))) + 2);
    return rect;
  }

  // The undistortion map of a distorted view (cached per camera).
  const ViewMap& MapFor(const Camera& view) {
    for (const ViewMap& map : view_maps)
      if (map.camera.width == view.width && map.camera.height == view.height && map.camera.K == view.K &&
          map.camera.dist == view.dist)
        return map;
    ViewMap map;
    map.camera = view;
    map.map_x.create(view.height, view.width, CV_32F);
    map.map_y.create(view.height, view.width, CV_32F);
    double min_x = 1e30, min_y = 1e30, max_x = -1e30, max_y = -1e30;
    for (int y = 0; y < view.height; ++y)
      for (int x = 0; x < view.width; ++x) {
        const Eigen::Vector2d ideal = view.UndistortPixel(Eigen::Vector2d(x, y));
        map.map_x.at<float>(y, x) = static_cast<float>(ideal.x());
        map.map_y.at<float>(y, x) = static_cast<float>(ideal.y());
        min_x = std::min(min_x, ideal.x());
        max_x = std::max(max_x, ideal.x());
        min_y = std::min(min_y, ideal.y());
        max_y = std::max(max_y, ideal.y());
      }
    const double w = view.width, h = view.height;
    min_x = std::max(min_x, -0.5 * w);
    min_y = std::max(min_y, -0.5 * h);
    max_x = std::min(max_x, 1.5 * w);
    max_y = std::min(max_y, 1.5 * h);
    map.x0 = static_cast<int>(std::floor(min_x)) - 1;
    map.y0 = static_cast<int>(std::floor(min_y)) - 1;
    map.width = static_cast<int>(std::ceil(max_x)) + 2 - map.x0;
    map.height = static_cast<int>(std::ceil(max_y)) + 2 - map.y0;
    map.map_x -= map.x0;
    map.map_y -= map.y0;
    if (view_maps.size() >= 8) view_maps.erase(view_maps.begin());
    view_maps.push_back(std::move(map));
    return view_maps.back();
  }

  RenderResult Render(const Camera& view, bool want_silhouette) {
    if (!frame_set) throw UsageError("ProjectiveTexturer::Render called before SetFrame");
    view.Check("novel view");
    context.MakeCurrent();
    Eigen::Matrix3d K = view.K;
    int width = view.width, height = view.height;
    const ViewMap* map = nullptr;
    if (view.has_distortion()) {
      map = &MapFor(view);
      K(0, 2) -= map->x0;
      K(1, 2) -= map->y0;
      width = map->width;
      height = map->height;
    }
    const Eigen::Matrix4d cam_from_world = CamFromWorld(view);
    // Both passes (and the clears) only touch the pixels the mesh can cover.
    const PixelRect rect = CoveredRect(cam_from_world, K, width, height);
    if (cpu_raster) {
      Camera ideal = view;  // the buffer's pinhole camera (the view itself when undistorted)
      ideal.K = K;
      ideal.width = width;
      ideal.height = height;
      ideal.dist.setZero();
      RenderCpu(ideal, rect);
    } else {
      RenderGl(view, K, width, height, cam_from_world, rect);
    }
    return Composite(view, width, height, map, want_silhouette);
  }

  // The blending's view-dependent input.
  BlendInput MakeBlendInput(const Camera& view) const {
    BlendInput in;
    in.view_center = view.center_in_world().cast<float>();
    in.depth_bias = static_cast<float>(options.depth_bias_m + proxy_bias_m);
    in.resolution_weight = static_cast<float>(options.resolution_weight);
    in.grazing_cos = static_cast<float>(options.grazing_cos);
    in.best_k = options.best_k;
    return in;
  }

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
  void RenderCpu(const Camera& ideal, const PixelRect& rect) {
    const int width = ideal.width, height = ideal.height;
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    readback.assign(pixels * 4, 0);
    if (view_inverse_depth.size() != pixels) {
      view_inverse_depth.assign(pixels, 0.0f);
      view_face_ids.assign(pixels, -1);
      view_written = PixelBox();
    }
    FillBox(view_inverse_depth.data(), width, view_written, 0.0f);
    FillBox(view_face_ids.data(), width, view_written, std::int32_t{-1});
    view_written = PixelBox();
    if (rect.x1 <= rect.x0 || rect.y1 <= rect.y0) return;
    if (raster_frames.empty()) raster_frames.resize(1);
    CpuRasterFrame& frame = raster_frames[0];
    view_rasterizer->Project(ideal, positions, &frame);
    // Two halves of the covered rows, drawn in parallel.
    const int middle = (rect.y0 + rect.y1) / 2;
    PixelBox boxes[2];
    auto draw = [&](int half) {
      boxes[half] = view_rasterizer->Draw(frame, half == 0 ? rect.y0 : middle, half == 0 ? middle : rect.y1,
                                          view_inverse_depth.data(), view_face_ids.data());
    };
    std::future<void> other = std::async(std::launch::async, draw, 1);
    try {
      draw(0);
    } catch (...) {
      other.wait();
      throw;
    }
    other.get();
    view_written = boxes[0].Union(boxes[1]);
    if (view_written.empty()) return;
    // Ray of pixel (u, v) in the world: D0 + u Du + v Dv (camera z = 1); X = C + z ray.
    const Eigen::Matrix3d world_from_pixel = ideal.rotation.transpose() * ideal.K.inverse();
    const Eigen::Vector3f Du = world_from_pixel.col(0).cast<float>(), Dv = world_from_pixel.col(1).cast<float>();
    const Eigen::Vector3f D0 = world_from_pixel.col(2).cast<float>();
    const Eigen::Vector3f C = ideal.center_in_world().cast<float>();
    const BlendInput in = MakeBlendInput(ideal);
    const Eigen::Vector3f fallback = options.fallback_color.cast<float>();
    const PixelBox box = view_written;
    auto blend_row = [&](int row) {
      const int y = box.y0 + row;
      const std::size_t offset = static_cast<std::size_t>(y) * width;
      int cached_face = -1;
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      for (int x = box.x0; x < box.x1; ++x) {
        const int face = view_face_ids[offset + x];
        if (face < 0) continue;
        const Eigen::Vector3f X = C + (D0 + static_cast<float>(x) * Du + static_cast<float>(y) * Dv) /
                                          view_inverse_depth[offset + x];
        const int a = mesh_faces(face, 0), b = mesh_faces(face, 1), c = mesh_faces(face, 2);
        auto vertex = [&](int v) { return Eigen::Vector3f(positions.row(v).transpose()); };
        if (face != cached_face) {
          const Eigen::Vector3f A = vertex(a);
          n = (vertex(b) - A).cross(vertex(c) - A);
          const float length = n.norm();
          n = length > 0.0f ? Eigen::Vector3f(n / length) : Eigen::Vector3f((C - X).normalized());
          cached_face = face;
        }
        const Eigen::Vector3f facing_n = n.dot(C - X) < 0.0f ? Eigen::Vector3f(-n) : n;
        std::uint8_t* out = readback.data() + 4 * (offset + x);
        if (!BlendPixel(in, blend_cameras, X, facing_n, out)) {
          Eigen::Vector3f base = fallback;
          if (has_colors) {
            // Barycentric coordinates of X in the face (its plane), as GL interpolates colours.
            const Eigen::Vector3f A = vertex(a), e1 = vertex(b) - A, e2 = vertex(c) - A, d = X - A;
            const float d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2), d1 = d.dot(e1), d2 = d.dot(e2);
            const float det = d11 * d22 - d12 * d12;
            float wb = 1.0f / 3.0f, wc = 1.0f / 3.0f;
            if (det > 0.0f) {
              wb = std::clamp((d22 * d1 - d12 * d2) / det, 0.0f, 1.0f);
              wc = std::clamp((d11 * d2 - d12 * d1) / det, 0.0f, 1.0f - wb);
            }
            base = (1.0f - wb - wc) * vertex_colors.row(a).transpose() + wb * vertex_colors.row(b).transpose() +
                   wc * vertex_colors.row(c).transpose();
          }
          for (int k = 0; k < 3; ++k)
            out[k] = static_cast<std::uint8_t>(std::lround(255.0f * std::clamp(base[k], 0.0f, 1.0f)));
        }
        out[3] = 255;
      }
    };
    ForRowBands(box.y1 - box.y0, blend_row);
  }

  // Render with GL into `readback` (buffer width x height with intrinsics K, RGBA8): the mesh into
  // a G-buffer, read back, blended on the CPU.
  void RenderGl(const Camera& view, const Eigen::Matrix3d& K, int width, int height,
                const Eigen::Matrix4d& cam_from_world, const PixelRect& rect) {
    EnsureFramebuffer(width, height);
    glViewport(0, 0, width, height);
    glEnable(GL_SCISSOR_TEST);
    glScissor(rect.x0, rect.y0, rect.x1 - rect.x0, rect.y1 - rect.y0);

    // Pass 1: the mesh into the G-buffer (cleared to w = 0: not covered).
    glBindFramebuffer(GL_FRAMEBUFFER, gbuffer_framebuffer);
    const GLfloat zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    for (int k = 0; k < 3; ++k) glClearBufferfv(GL_COLOR, k, zero);
    const GLfloat far_depth = 1.0f;
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
    render_internal::SetMeshRasterState(options.cull_back_faces, GL_LEQUAL);
    const Eigen::Matrix4f clip_from_world =
        (ClipFromCamera(K, width, height, renderer_options.near_m, renderer_options.far_m) * cam_from_world)
            .cast<float>();
    const Eigen::Vector3f view_center = view.center_in_world().cast<float>();
    glUseProgram(gbuffer_program);
    glUniformMatrix4fv(glGetUniformLocation(gbuffer_program, "clip_from_world"), 1, GL_FALSE, clip_from_world.data());
    glUniform3fv(glGetUniformLocation(gbuffer_program, "view_center"), 1, view_center.data());
    glUniform1i(glGetUniformLocation(gbuffer_program, "use_vertex_colors"), has_colors ? 1 : 0);
    const Eigen::Vector3f fallback = options.fallback_color.cast<float>();
    glUniform3fv(glGetUniformLocation(gbuffer_program, "fallback"), 1, fallback.data());
    glBindVertexArray(vertex_array);
    glDrawElements(GL_TRIANGLES, num_faces * 3, GL_UNSIGNED_INT, nullptr);
    glDisable(GL_CULL_FACE);
    glDisable(GL_DEPTH_TEST);

    glDisable(GL_SCISSOR_TEST);

    // Pass 2: blending, once per covered pixel, on the CPU (all cores): on a software rasteriser
    // a fragment shader pays for every camera's tests on every pixel, the CPU only for the cameras
    // a point faces. Uncovered pixels stay transparent black, so that the distortion remap below
    // interpolates premultiplied colour; the background colour is composited afterwards.
    readback.assign(static_cast<std::size_t>(width) * height * 4, 0);
    if (rect.x1 > rect.x0 && rect.y1 > rect.y0) {
      const int rect_width = rect.x1 - rect.x0, rect_height = rect.y1 - rect.y0;
      const std::size_t rect_pixels = static_cast<std::size_t>(rect_width) * rect_height;
      gbuffer_position.resize(4 * rect_pixels);
      gbuffer_normal.resize(4 * rect_pixels);
      gbuffer_base.resize(4 * rect_pixels);
      glReadBuffer(GL_COLOR_ATTACHMENT0);
      glReadPixels(rect.x0, rect.y0, rect_width, rect_height, GL_RGBA, GL_FLOAT, gbuffer_position.data());
      glReadBuffer(GL_COLOR_ATTACHMENT1);
      glReadPixels(rect.x0, rect.y0, rect_width, rect_height, GL_RGBA, GL_FLOAT, gbuffer_normal.data());
      glReadBuffer(GL_COLOR_ATTACHMENT2);
      glReadPixels(rect.x0, rect.y0, rect_width, rect_height, GL_RGBA, GL_UNSIGNED_BYTE, gbuffer_base.data());
      CheckGl("rendering view " + view.name);
      const BlendInput in = MakeBlendInput(view);
      auto blend_row = [&](int y) {
        for (int x = 0; x < rect_width; ++x) {
          const std::size_t g = static_cast<std::size_t>(y) * rect_width + x;
          if (gbuffer_position[4 * g + 3] == 0.0f) continue;  // not covered
          const float* P = gbuffer_position.data() + 4 * g;
          const float* N = gbuffer_normal.data() + 4 * g;
          std::uint8_t* out = readback.data() + 4 * (static_cast<std::size_t>(rect.y0 + y) * width + rect.x0 + x);
          if (!BlendPixel(in, blend_cameras, Eigen::Vector3f(P[0], P[1], P[2]), Eigen::Vector3f(N[0], N[1], N[2]), out))
            std::copy_n(gbuffer_base.data() + 4 * g, 3, out);
          out[3] = 255;
        }
      };
      ForRowBands(rect_height, blend_row);
    }
  }

  // The output image of `view` from `readback` (width x height, RGBA8 premultiplied by coverage):
  // remapped through the distortion map when there is one, the background composited.
  RenderResult Composite(const Camera& view, int width, int height, const ViewMap* map, bool want_silhouette) {
    RenderResult result;
    cv::Mat rgba(height, width, CV_8UC4, readback.data());
    cv::Mat out_rgba;
    if (map != nullptr) {
      // Bilinear in the ideal buffer; as in MeshRenderer, a pixel is covered when the
      // interpolated coverage is >= 0.5, and its colour averages the covered samples only.
      cv::remap(rgba, out_rgba, map->map_x, map->map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    } else {
      out_rgba = rgba;
    }
    result.color = Image(view.width, view.height, 3);
    if (want_silhouette) result.silhouette = Image(view.width, view.height, 1);
    const std::size_t pixels = static_cast<std::size_t>(view.width) * view.height;
    const std::uint8_t* in = out_rgba.ptr<std::uint8_t>();
    std::uint8_t* color = result.color.data.data();
    std::uint8_t background[3];
    for (int c = 0; c < 3; ++c)
      background[c] = static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(options.background[c], 0.0, 1.0)));
    for (std::size_t p = 0; p < pixels; ++p) {
      const int alpha = in[4 * p + 3];
      const bool covered = alpha >= 128;
      for (int c = 0; c < 3; ++c) {
        const int value = in[4 * p + c];
        color[3 * p + c] = !covered ? background[c]
                           : alpha == 255 ? static_cast<std::uint8_t>(value)
                                          : static_cast<std::uint8_t>(std::min(255, (value * 255 + alpha / 2) / alpha));
      }
      if (want_silhouette) result.silhouette.data[p] = covered ? 255 : 0;
    }
    return result;
  }

  // The input cameras as the blending sees them (after the frame's images, maps and gains).
  void SetBlendCameras() {
    blend_cameras.clear();
    for (std::size_t i = 0; i < cameras.size(); ++i) {
      const Camera& camera = cameras[i];
      BlendCamera b;
      b.rotation = camera.rotation.cast<float>();
      b.translation = camera.translation.cast<float>();
      b.center = camera.center_in_world().cast<float>();
      b.gain = (view_gains.empty() ? gains[i] : gains[i].cwiseProduct(view_gains[i])).cast<float>();
      b.fx = static_cast<float>(camera.K(0, 0));
      b.fy = static_cast<float>(camera.K(1, 1));
      b.cx = static_cast<float>(camera.K(0, 2));
      b.cy = static_cast<float>(camera.K(1, 2));
      b.skew = static_cast<float>(camera.K(0, 1));
      b.k1 = static_cast<float>(camera.dist[0]);
      b.k2 = static_cast<float>(camera.dist[1]);
      b.p1 = static_cast<float>(camera.dist[2]);
      b.p2 = static_cast<float>(camera.dist[3]);
      b.k3 = static_cast<float>(camera.dist[4]);
      b.distorted = b.k1 != 0.0f || b.k2 != 0.0f || b.p1 != 0.0f || b.p2 != 0.0f || b.k3 != 0.0f;
      b.width = camera.width;
      b.height = camera.height;
      b.image = frame_images[i].data.data();
      b.map_width = vis_cameras[i].width;
      b.map_height = vis_cameras[i].height;
      b.map_scale_x = static_cast<float>(b.map_width) / static_cast<float>(camera.width);
      b.map_scale_y = static_cast<float>(b.map_height) / static_cast<float>(camera.height);
      b.depth_feather = depth_feather[i].data();
      blend_cameras.push_back(b);
    }
  }
};

ProjectiveTexturer::ProjectiveTexturer(const Mesh& mesh, const ProjectiveTextureOptions& options,
                                       const MeshRendererOptions& renderer) {
  options.Check();
  renderer.Check();
  impl_ = std::make_unique<Impl>(mesh, options, renderer);
}

ProjectiveTexturer::~ProjectiveTexturer() = default;

void ProjectiveTexturer::SetFrame(const RowMatrixX3d& vertices, const std::vector<Camera>& cameras,
                                  const std::vector<Image>& images, const std::vector<Image>& masks) {
  impl_->SetFrame(vertices, cameras, images, masks);
}

RenderResult ProjectiveTexturer::Render(const Camera& view, bool want_silhouette) {
  return impl_->Render(view, want_silhouette);
}

void ProjectiveTexturer::SetViewGains(const std::vector<Eigen::Vector3d>& gains) {
  Impl& s = *impl_;
  if (!s.frame_set) throw UsageError("ProjectiveTexturer::SetViewGains: SetFrame was not called");
  if (!gains.empty() && gains.size() != s.cameras.size())
    throw UsageError("ProjectiveTexturer::SetViewGains: " + std::to_string(gains.size()) + " gains for " +
                     std::to_string(s.cameras.size()) + " cameras");
  for (std::size_t i = 0; i < gains.size(); ++i)
    if (!gains[i].allFinite() || gains[i].minCoeff() <= 0.0)
      throw InputError("colour gains", "camera " + s.cameras[i].name + ": gains must be finite and positive");
  s.view_gains = gains;
  s.SetBlendCameras();
}

const TextureFrameInfo& ProjectiveTexturer::frame_info() const { return impl_->info; }

}  // namespace confluent
