// ProjectiveTexturer: unstructured-lumigraph projective texturing with a GL fragment shader.
//
// SetFrame renders each input camera's depth map with MeshRenderer (exact lens distortion),
// derives a feather map on the CPU (distance to the mesh outline, to depth discontinuities and
// to the mask outline), and uploads images and (depth, feather) pairs as texture arrays. Render
// rasterises the mesh into the novel view; each fragment projects its world point into every
// input camera (distortion applied per fragment), tests visibility against the depth map
// (shadow-map style) and blends the best k cameras.

#include "render/projective_texture.h"
#include "render/gl_program.h"

#include <epoxy/gl.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "calib/capture.h"
#include "core/cv_interop.h"
#include "core/error.h"

namespace confluent {
namespace {

using render_internal::CamFromWorld;
using render_internal::ClipFromCamera;
using render_internal::LinkProgram;

constexpr int kMaxCameras = 32;

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

// See the header for the weighting. Uniform arrays are indexed by input camera. BEST_K is
// defined at compile time, so that the running best-(k+1) list below unrolls into registers
// (dynamically indexed local arrays are very slow on llvmpipe).
constexpr const char* kFragmentShader = R"(
#define MAX_CAMERAS 32
#define SLOTS (BEST_K + 1)
in vec3 v_position;
in vec3 v_color;
layout(location = 0) out vec4 out_color;
uniform int num_cameras;
uniform mat3 cam_rotation[MAX_CAMERAS];
uniform vec3 cam_translation[MAX_CAMERAS];
uniform vec4 cam_intrinsics[MAX_CAMERAS];  // fx fy cx cy
uniform float cam_skew[MAX_CAMERAS];
uniform vec4 cam_dist[MAX_CAMERAS];        // k1 k2 p1 p2
uniform float cam_k3[MAX_CAMERAS];
uniform vec2 cam_size[MAX_CAMERAS];
uniform vec3 cam_center[MAX_CAMERAS];
uniform vec3 cam_gain[MAX_CAMERAS];
uniform vec2 atlas_size;
uniform sampler2DArray images;
uniform sampler2DArray depth_feather;
uniform vec3 view_center;
uniform float depth_bias;
uniform float resolution_weight;
uniform float grazing_cos;
uniform int use_vertex_colors;
uniform vec3 fallback;

void main() {
  vec3 X = v_position;
  vec3 to_view = view_center - X;
  float view_distance = max(length(to_view), 1e-6);
  to_view /= view_distance;
  vec3 n = cross(dFdx(X), dFdy(X));
  float n_length = length(n);
  n = n_length > 0.0 ? n / n_length : to_view;
  if (dot(n, to_view) < 0.0) n = -n;

  // The SLOTS smallest penalties so far, ascending, with their colour and quality.
  float slot_penalty[SLOTS];
  vec3 slot_color[SLOTS];
  float slot_quality[SLOTS];
  for (int s = 0; s < SLOTS; ++s) {
    slot_penalty[s] = 1e30;
    slot_color[s] = vec3(0.0);
    slot_quality[s] = 0.0;
  }
  int count = 0;
  for (int i = 0; i < num_cameras; ++i) {
    vec3 p = cam_rotation[i] * X + cam_translation[i];
    if (p.z <= 1e-6) continue;
    vec2 xn = p.xy / p.z;
    vec4 d = cam_dist[i];
    float k3 = cam_k3[i];
    if (d != vec4(0.0) || k3 != 0.0) {
      float r2 = dot(xn, xn);
      float radial = 1.0 + r2 * (d.x + r2 * (d.y + r2 * k3));
      xn = vec2(xn.x * radial + 2.0 * d.z * xn.x * xn.y + d.w * (r2 + 2.0 * xn.x * xn.x),
                xn.y * radial + d.z * (r2 + 2.0 * xn.y * xn.y) + 2.0 * d.w * xn.x * xn.y);
    }
    vec4 K = cam_intrinsics[i];
    vec2 pixel = vec2(K.x * xn.x + cam_skew[i] * xn.y + K.z, K.y * xn.y + K.w);
    vec2 size = cam_size[i];
    if (pixel.x < -0.5 || pixel.y < -0.5 || pixel.x > size.x - 0.5 || pixel.y > size.y - 0.5) continue;
    // Shadow-map test against the farthest of the 4 surrounding depth texels (lenient on slanted
    // surfaces; occlusion edges are feathered anyway), feather from the nearest texel.
    vec2 uv = (pixel + 0.5) / atlas_size;
    vec4 depths = textureGather(depth_feather, vec3(uv, float(i)), 0);
    float depth = max(max(depths.x, depths.y), max(depths.z, depths.w));
    if (depth <= 0.0 || p.z > depth + depth_bias) continue;
    ivec2 texel = clamp(ivec2(floor(pixel + 0.5)), ivec2(0), ivec2(size) - 1);
    float feather = texelFetch(depth_feather, ivec3(texel, i), 0).g;
    if (feather <= 0.0) continue;
    vec3 to_camera = cam_center[i] - X;
    float camera_distance = length(to_camera);
    to_camera /= camera_distance;
    float facing = dot(n, to_camera);
    if (facing <= 0.0) continue;
    float q = feather;
    if (grazing_cos > 0.0) q *= smoothstep(0.0, grazing_cos, facing);
    if (q <= 0.0) continue;
    // Angle between the rays: sqrt(2 - 2 cos) is the chord, within 5% of the angle below 60 deg.
    float angle = sqrt(max(2.0 - 2.0 * dot(to_view, to_camera), 0.0));
    float penalty = max(angle + resolution_weight * max(0.0, camera_distance - view_distance) / view_distance, 1e-4);
    vec3 color = texture(images, vec3(uv, float(i))).rgb * cam_gain[i];
    ++count;
    for (int s = 0; s < SLOTS; ++s) {  // insertion into the sorted slots
      bool take = penalty < slot_penalty[s];
      float kept_penalty = slot_penalty[s];
      vec3 kept_color = slot_color[s];
      float kept_quality = slot_quality[s];
      slot_penalty[s] = take ? penalty : kept_penalty;
      slot_color[s] = take ? color : kept_color;
      slot_quality[s] = take ? q : kept_quality;
      penalty = take ? kept_penalty : penalty;
      color = take ? kept_color : color;
      q = take ? kept_quality : q;
    }
  }

  vec3 base = use_vertex_colors != 0 ? v_color : fallback;
  // Threshold t: the (k+1)-th smallest penalty, or pi when k or fewer cameras see X.
  float threshold = count > BEST_K ? slot_penalty[BEST_K] : 3.14159265;
  vec3 sum = vec3(0.0);
  float total = 0.0;
  for (int s = 0; s < BEST_K; ++s) {
    float w = slot_penalty[s] < threshold ? (1.0 - slot_penalty[s] / threshold) / slot_penalty[s] * slot_quality[s] : 0.0;
    sum += w * slot_color[s];
    total += w;
  }
  out_color = vec4(total > 0.0 ? clamp(sum / total, 0.0, 1.0) : base, 1.0);
}
)";

float Smoothstep(float edge, float x) {
  if (edge <= 0.0f) return 1.0f;
  const float t = std::clamp(x / edge, 0.0f, 1.0f);
  return t * t * (3.0f - 2.0f * t);
}

// Per-camera data kept on the CPU for the colour balance fit.
struct CameraFrame {
  Camera camera;
  Image depth;           // float camera z, 0 = background
  cv::Mat feather;       // CV_32F in [0,1]
  const Image* image = nullptr;
  int visible_pixels = 0;
};

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
  if (colour_balance_samples < 1) throw UsageError("colour_balance_samples must be >= 1");
  if (!fallback_color.allFinite() || !background.allFinite()) throw UsageError("colours must be finite");
}

struct ProjectiveTexturer::Impl {
  ProjectiveTextureOptions options;
  MeshRendererOptions renderer_options;
  MeshRenderer renderer;
  int mesh_handle = 0;
  EglContext context;
  int num_vertices = 0;
  int num_faces = 0;
  bool has_colors = false;

  GLuint program = 0;
  GLuint vertex_array = 0;
  GLuint position_buffer = 0;
  GLuint color_buffer = 0;
  GLuint index_buffer = 0;
  GLuint image_array = 0;
  GLuint depth_array = 0;
  int atlas_width = 0, atlas_height = 0, atlas_layers = 0;
  GLuint framebuffer = 0, color_renderbuffer = 0, depth_renderbuffer = 0;
  int fb_width = 0, fb_height = 0;
  std::vector<float> scratch;
  std::vector<std::uint8_t> readback;

  bool frame_set = false;
  std::vector<Camera> cameras;
  std::vector<Eigen::Vector3d> gains;
  TextureFrameInfo info;

  // Cached undistortion map of the last distorted view.
  struct ViewMap {
    Camera camera;
    cv::Mat map_x, map_y;  // output pixel -> ideal buffer position
    int x0 = 0, y0 = 0, width = 0, height = 0;
  };
  std::vector<ViewMap> view_maps;

  Impl(const Mesh& mesh, const ProjectiveTextureOptions& texture_options, const MeshRendererOptions& render_options)
      : options(texture_options), renderer_options(render_options), renderer(render_options),
        context(render_options.context) {
    mesh_handle = renderer.AddMesh(mesh, "mesh");  // validates the mesh
    num_vertices = mesh.num_vertices();
    num_faces = mesh.num_faces();
    has_colors = mesh.has_colors();
    context.MakeCurrent();
    const std::string fragment = "#version 430 core\n#define BEST_K " + std::to_string(options.best_k) + "\n" +
                                 kFragmentShader;
    program = LinkProgram(kVertexShader, fragment, "projective texture");
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
    glBindVertexArray(0);
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
    glDeleteProgram(program);
    const GLuint buffers[] = {position_buffer, color_buffer, index_buffer};
    glDeleteBuffers(3, buffers);
    glDeleteVertexArrays(1, &vertex_array);
    const GLuint textures[] = {image_array, depth_array};
    glDeleteTextures(2, textures);
    glDeleteFramebuffers(1, &framebuffer);
    const GLuint renderbuffers[] = {color_renderbuffer, depth_renderbuffer};
    glDeleteRenderbuffers(2, renderbuffers);
  }

  static void CheckGl(const std::string& step) {
    const GLenum error = glGetError();
    if (error != GL_NO_ERROR) {
      std::ostringstream out;
      out << "OpenGL: projective texturing " << step << " failed (GL error 0x" << std::hex << error << ")";
      throw RenderContextError(out.str());
    }
  }

  void UploadPositions(const RowMatrixX3d& vertices) {
    scratch.resize(static_cast<std::size_t>(num_vertices) * 3);
    for (int v = 0; v < num_vertices; ++v)
      for (int k = 0; k < 3; ++k) scratch[3 * v + k] = static_cast<float>(vertices(v, k));
    glBindBuffer(GL_ARRAY_BUFFER, position_buffer);
    glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(scratch.size() * sizeof(float)), scratch.data());
  }

  // Feather map of one camera: smoothstep(0, feather_px, distance to the nearest outline pixel
  // of the mesh, depth discontinuity or mask outline); 0 outside the mesh or the mask.
  cv::Mat FeatherMap(const Image& depth, const Image& mask, int* visible) const {
    const int w = depth.width, h = depth.height;
    cv::Mat feather(h, w, CV_32F, cv::Scalar(0.0f));
    // Region of interest: covered pixels plus the feather margin.
    int min_x = w, min_y = h, max_x = -1, max_y = -1, count = 0;
    const float* z = depth.ptr<float>();
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (z[static_cast<std::size_t>(y) * w + x] > 0.0f) {
          min_x = std::min(min_x, x);
          max_x = std::max(max_x, x);
          min_y = std::min(min_y, y);
          max_y = std::max(max_y, y);
          ++count;
        }
    *visible = count;
    if (count == 0) return feather;
    const int margin = static_cast<int>(std::ceil(options.feather_px)) + 2;
    const int x0 = std::max(0, min_x - margin), y0 = std::max(0, min_y - margin);
    const int x1 = std::min(w - 1, max_x + margin), y1 = std::min(h - 1, max_y + margin);
    const int rw = x1 - x0 + 1, rh = y1 - y0 + 1;
    const bool use_mask = !mask.empty();
    auto covered = [&](int x, int y) { return z[static_cast<std::size_t>(y) * w + x] > 0.0f; };
    auto in_mask = [&](int x, int y) { return !use_mask || mask.at<std::uint8_t>(x, y) != 0; };
    if (options.feather_px <= 0.0) {
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) feather.at<float>(y, x) = covered(x, y) && in_mask(x, y) ? 1.0f : 0.0f;
      return feather;
    }
    // Edge pixels are 0, others 255 (distanceTransform measures the distance to the nearest 0).
    cv::Mat not_edge(rh, rw, CV_8U, cv::Scalar(255));
    const float jump = static_cast<float>(options.depth_edge_m);
    const bool mask_edges = use_mask && options.feather_mask_edges;
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const bool c = covered(x, y);
        const float d = z[static_cast<std::size_t>(y) * w + x];
        bool edge = false;
        const int nx[4] = {x - 1, x + 1, x, x};
        const int ny[4] = {y, y, y - 1, y + 1};
        for (int k = 0; k < 4 && !edge; ++k) {
          if (nx[k] < 0 || ny[k] < 0 || nx[k] >= w || ny[k] >= h) {
            edge = c;  // the image border is an edge of what the camera sees
            continue;
          }
          const float dn = z[static_cast<std::size_t>(ny[k]) * w + nx[k]];
          if ((dn > 0.0f) != c) edge = true;
          else if (c && std::abs(dn - d) > jump) edge = true;
          else if (mask_edges && (mask.at<std::uint8_t>(nx[k], ny[k]) != 0) != (mask.at<std::uint8_t>(x, y) != 0))
            edge = true;
        }
        if (edge) not_edge.at<std::uint8_t>(y - y0, x - x0) = 0;
      }
    cv::Mat distance;
    cv::distanceTransform(not_edge, distance, cv::DIST_L2, cv::DIST_MASK_5);
    const float width = static_cast<float>(options.feather_px);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x)
        if (covered(x, y) && in_mask(x, y))
          // +0.5: an edge pixel itself is half a pixel from the outline.
          feather.at<float>(y, x) = Smoothstep(width, distance.at<float>(y - y0, x - x0) + 0.5f);
    return feather;
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
        const float depth = frame.depth.at<float>(px, py);
        if (depth <= 0.0f || frame.camera.PointInCamera(X).z() > depth + options.depth_bias_m) continue;
        if (frame.feather.at<float>(py, px) < 0.99f) continue;
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
    renderer.UpdateVertices(mesh_handle, vertices);  // throws InputError for NaN vertices

    std::vector<CameraFrame> frames(n);
    info = TextureFrameInfo();
    RenderRequest request;
    request.color = false;
    request.depth = true;
    request.cull_back_faces = options.cull_back_faces;
    for (int i = 0; i < n; ++i) {
      frames[i].camera = input_cameras[i];
      frames[i].depth = renderer.Render(input_cameras[i], request).depth;
      frames[i].image = rgb[i];
      static const Image kNoMask;
      frames[i].feather = FeatherMap(frames[i].depth, masks.empty() ? kNoMask : masks[i], &frames[i].visible_pixels);
      info.visible_pixels.push_back(frames[i].visible_pixels);
    }
    gains = options.colour_balance ? FitGains(vertices, frames) : std::vector<Eigen::Vector3d>(n, Eigen::Vector3d::Ones());
    info.colour_gains = gains;

    // Upload to the texture arrays (layers sized to the largest camera).
    context.MakeCurrent();
    int width = 1, height = 1;
    for (const Camera& camera : input_cameras) {
      width = std::max(width, camera.width);
      height = std::max(height, camera.height);
    }
    const int layers = std::max(n, 1);
    if (width != atlas_width || height != atlas_height || layers != atlas_layers) {
      const GLuint old[] = {image_array, depth_array};
      glDeleteTextures(2, old);
      glGenTextures(1, &image_array);
      glBindTexture(GL_TEXTURE_2D_ARRAY, image_array);
      glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_RGBA8, width, height, layers);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
      glGenTextures(1, &depth_array);
      glBindTexture(GL_TEXTURE_2D_ARRAY, depth_array);
      glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_RG32F, width, height, layers);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
      glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
      const float border[4] = {0.0f, 0.0f, 0.0f, 0.0f};
      glTexParameterfv(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_BORDER_COLOR, border);
      atlas_width = width;
      atlas_height = height;
      atlas_layers = layers;
    }
    std::vector<float> depth_feather;
    for (int i = 0; i < n; ++i) {
      const int w = input_cameras[i].width, h = input_cameras[i].height;
      glBindTexture(GL_TEXTURE_2D_ARRAY, image_array);
      glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, i, w, h, 1, GL_RGB, GL_UNSIGNED_BYTE, rgb[i]->data.data());
      depth_feather.resize(static_cast<std::size_t>(w) * h * 2);
      const float* z = frames[i].depth.ptr<float>();
      for (int y = 0; y < h; ++y) {
        const float* f = frames[i].feather.ptr<float>(y);
        for (int x = 0; x < w; ++x) {
          const std::size_t p = static_cast<std::size_t>(y) * w + x;
          depth_feather[2 * p] = z[p];
          depth_feather[2 * p + 1] = f[x];
        }
      }
      glBindTexture(GL_TEXTURE_2D_ARRAY, depth_array);
      glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, i, w, h, 1, GL_RG, GL_FLOAT, depth_feather.data());
    }
    UploadPositions(vertices);
    CheckGl("upload");
    cameras = input_cameras;
    frame_set = true;
  }

  void EnsureFramebuffer(int width, int height) {
    if (framebuffer != 0 && width == fb_width && height == fb_height) return;
    if (framebuffer == 0) {
      glGenFramebuffers(1, &framebuffer);
      glGenRenderbuffers(1, &color_renderbuffer);
      glGenRenderbuffers(1, &depth_renderbuffer);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, color_renderbuffer);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_renderbuffer);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_renderbuffer);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_renderbuffer);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw RenderContextError("OpenGL: projective texture framebuffer " + std::to_string(width) + "x" +
                               std::to_string(height) + " is incomplete");
    fb_width = width;
    fb_height = height;
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
    EnsureFramebuffer(width, height);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glViewport(0, 0, width, height);
    // Cleared to transparent black, so that the distortion remap below interpolates
    // premultiplied colour; the background colour is composited afterwards.
    const GLfloat transparent[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    glClearBufferfv(GL_COLOR, 0, transparent);
    const GLfloat far_depth = 1.0f;
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
    render_internal::SetMeshRasterState(options.cull_back_faces, GL_LEQUAL);

    const Eigen::Matrix4d cam_from_world = CamFromWorld(view);
    const Eigen::Matrix4f clip_from_world =
        (ClipFromCamera(K, width, height, renderer_options.near_m, renderer_options.far_m) * cam_from_world)
            .cast<float>();
    glUseProgram(program);
    glBindVertexArray(vertex_array);
    glUniformMatrix4fv(glGetUniformLocation(program, "clip_from_world"), 1, GL_FALSE, clip_from_world.data());
    SetCameraUniforms(view);
    if (options.depth_prepass) {
      // Depth only; the expensive shader then runs once per visible pixel.
      glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
      glUniform1i(glGetUniformLocation(program, "num_cameras"), 0);
      glDrawElements(GL_TRIANGLES, num_faces * 3, GL_UNSIGNED_INT, nullptr);
      glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
      glDepthMask(GL_FALSE);
    }
    glUniform1i(glGetUniformLocation(program, "num_cameras"), static_cast<int>(cameras.size()));
    glDrawElements(GL_TRIANGLES, num_faces * 3, GL_UNSIGNED_INT, nullptr);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);
    glBindVertexArray(0);

    readback.resize(static_cast<std::size_t>(width) * height * 4);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, readback.data());
    CheckGl("rendering view " + view.name);

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

  void SetCameraUniforms(const Camera& view) {
    const int n = static_cast<int>(cameras.size());
    std::vector<float> rotation(9 * std::max(n, 1)), translation(3 * std::max(n, 1)), intrinsics(4 * std::max(n, 1)),
        skew(std::max(n, 1)), dist(4 * std::max(n, 1)), k3(std::max(n, 1)), size(2 * std::max(n, 1)),
        center(3 * std::max(n, 1)), gain(3 * std::max(n, 1));
    for (int i = 0; i < n; ++i) {
      const Camera& camera = cameras[i];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) rotation[9 * i + 3 * c + r] = static_cast<float>(camera.rotation(r, c));  // column-major
      const Eigen::Vector3d cc = camera.center_in_world();
      for (int k = 0; k < 3; ++k) {
        translation[3 * i + k] = static_cast<float>(camera.translation[k]);
        center[3 * i + k] = static_cast<float>(cc[k]);
        gain[3 * i + k] = static_cast<float>(gains[i][k]);
      }
      intrinsics[4 * i] = static_cast<float>(camera.K(0, 0));
      intrinsics[4 * i + 1] = static_cast<float>(camera.K(1, 1));
      intrinsics[4 * i + 2] = static_cast<float>(camera.K(0, 2));
      intrinsics[4 * i + 3] = static_cast<float>(camera.K(1, 2));
      skew[i] = static_cast<float>(camera.K(0, 1));
      for (int k = 0; k < 4; ++k) dist[4 * i + k] = static_cast<float>(camera.dist[k]);
      k3[i] = static_cast<float>(camera.dist[4]);
      size[2 * i] = static_cast<float>(camera.width);
      size[2 * i + 1] = static_cast<float>(camera.height);
    }
    auto loc = [&](const char* name) { return glGetUniformLocation(program, name); };
    if (n > 0) {
      glUniformMatrix3fv(loc("cam_rotation"), n, GL_FALSE, rotation.data());
      glUniform3fv(loc("cam_translation"), n, translation.data());
      glUniform4fv(loc("cam_intrinsics"), n, intrinsics.data());
      glUniform1fv(loc("cam_skew"), n, skew.data());
      glUniform4fv(loc("cam_dist"), n, dist.data());
      glUniform1fv(loc("cam_k3"), n, k3.data());
      glUniform2fv(loc("cam_size"), n, size.data());
      glUniform3fv(loc("cam_center"), n, center.data());
      glUniform3fv(loc("cam_gain"), n, gain.data());
    }
    glUniform2f(loc("atlas_size"), static_cast<float>(atlas_width), static_cast<float>(atlas_height));
    const Eigen::Vector3f view_center = view.center_in_world().cast<float>();
    glUniform3fv(loc("view_center"), 1, view_center.data());
    glUniform1f(loc("depth_bias"), static_cast<float>(options.depth_bias_m));
    glUniform1f(loc("resolution_weight"), static_cast<float>(options.resolution_weight));
    glUniform1f(loc("grazing_cos"), static_cast<float>(options.grazing_cos));
    glUniform1i(loc("use_vertex_colors"), has_colors ? 1 : 0);
    const Eigen::Vector3f fallback = options.fallback_color.cast<float>();
    glUniform3fv(loc("fallback"), 1, fallback.data());
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D_ARRAY, image_array);
    glUniform1i(loc("images"), 0);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D_ARRAY, depth_array);
    glUniform1i(loc("depth_feather"), 1);
    glActiveTexture(GL_TEXTURE0);
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

const TextureFrameInfo& ProjectiveTexturer::frame_info() const { return impl_->info; }

}  // namespace confluent
