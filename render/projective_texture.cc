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
// The depth maps and SetFrame are in render/texture_depth_maps.cc, the colour balance fit in
// render/texture_colour_balance.cc, Render (CPU and GL paths) in render/texture_render.cc;
// ProjectiveTexturer::Impl is declared in render/projective_texture_impl.h.

#include "render/projective_texture.h"
#include "render/projective_texture_impl.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cstdint>
#include <sstream>

#include "core/error.h"

namespace confluent {
namespace {

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
}  // namespace

void ProjectiveTextureOptions::Check() const {
  const std::string owner = "ProjectiveTextureOptions.";
  RequireOption(best_k >= 1 && best_k <= 8, owner + "best_k", best_k, "in 1..8");
  RequireOption(depth_bias_m >= 0.0 && std::isfinite(depth_bias_m), owner + "depth_bias_m", depth_bias_m,
                ">= 0 and finite");
  RequireOption(feather_px >= 0.0 && std::isfinite(feather_px), owner + "feather_px", feather_px, ">= 0 and finite");
  RequireOption(depth_edge_m > 0.0 && std::isfinite(depth_edge_m), owner + "depth_edge_m", depth_edge_m,
                "> 0 and finite");
  RequireOption(resolution_weight >= 0.0 && std::isfinite(resolution_weight), owner + "resolution_weight",
                resolution_weight, ">= 0 and finite");
  RequireOption(grazing_cos >= 0.0 && grazing_cos <= 1.0, owner + "grazing_cos", grazing_cos, "in [0, 1]");
  RequireOption(visibility_scale > 0.0 && visibility_scale <= 1.0, owner + "visibility_scale", visibility_scale,
                "in (0, 1]");
  RequireOption(visibility_faces >= 0, owner + "visibility_faces", visibility_faces, ">= 0");
  RequireOption(colour_balance_samples >= 1, owner + "colour_balance_samples", colour_balance_samples, ">= 1");
  RequireOption(fallback_color.allFinite(), owner + "fallback_color",
                {fallback_color.x(), fallback_color.y(), fallback_color.z()}, "finite");
  RequireOption(background.allFinite(), owner + "background", {background.x(), background.y(), background.z()},
                "finite");
}
ProjectiveTexturer::Impl::Impl(const Mesh& mesh, const ProjectiveTextureOptions& texture_options,
                               const MeshRendererOptions& render_options)
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

ProjectiveTexturer::Impl::~Impl() {
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

void ProjectiveTexturer::Impl::CheckGl(const std::string& step) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    std::ostringstream out;
    out << "OpenGL: projective texturing " << step << " failed (GL error 0x" << std::hex << error << ")";
    throw RenderContextError(out.str());
  }
}

// The checks of MeshRenderer::AddMesh that matter here: finite vertices, face indices in range,
// colours.
void ProjectiveTexturer::Impl::ValidateMesh(const Mesh& mesh) {
  CheckVertices(mesh.vertices, "mesh");
  CheckFaceIndices(mesh, "mesh");
  const int n = mesh.num_vertices();
  if (mesh.colors.rows() != 0 && mesh.colors.rows() != n)
    throw InputError("mesh", "has " + std::to_string(mesh.colors.rows()) + " vertex colours for " +
                                 std::to_string(n) + " vertices");
  if (mesh.has_colors() && !mesh.colors.allFinite()) throw InputError("mesh", "vertex colours contain NaN");
}

// Keeps the vertices in single precision and, when GL draws, uploads them.
void ProjectiveTexturer::Impl::UploadPositions(const RowMatrixX3d& vertices) {
  positions = vertices.cast<float>();
  if (cpu_raster) return;
  glBindBuffer(GL_ARRAY_BUFFER, position_buffer);
  glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(positions.size() * sizeof(float)), positions.data());
}

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
