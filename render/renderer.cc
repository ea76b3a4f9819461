// MeshRenderer: OpenGL 4.3 core rasterisation of meshes into calibrated cameras.
// The GLSL lives in renderer_shaders.h, the GL resources it holds in renderer_resources.h.

#include "render/renderer.h"
#include "render/gl_program.h"
#include "render/renderer_resources.h"
#include "render/renderer_shaders.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <utility>

#include "core/image_io.h"

namespace confluent {
namespace {

using render_internal::CamFromWorld;
using render_internal::CheckFaceIndices;
using render_internal::CheckVertices;
using render_internal::ClipFromCamera;
using render_internal::LinkProgram;
using namespace mesh_renderer_internal;

void SetMatrix(GLuint program, const char* name, const Eigen::Matrix4d& matrix) {
  const Eigen::Matrix4f m = matrix.cast<float>();  // column-major, as GL expects
  glUniformMatrix4fv(glGetUniformLocation(program, name), 1, GL_FALSE, m.data());
}

float EncodeSrgb(double linear) {
  const double c = std::clamp(linear, 0.0, 1.0);
  return static_cast<float>(c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055);
}
std::string Where(int row, const char* what) {
  return std::string(what) + " " + std::to_string(row);
}

// Area-weighted vertex normals (unnormalised; the shader normalises).
RowMatrixX3d VertexNormals(const RowMatrixX3d& vertices, const RowMatrixX3i& faces) {
  RowMatrixX3d normals = RowMatrixX3d::Zero(vertices.rows(), 3);
  for (int f = 0; f < faces.rows(); ++f) {
    const int a = faces(f, 0), b = faces(f, 1), c = faces(f, 2);
    const Eigen::Vector3d n =
        (vertices.row(b) - vertices.row(a)).transpose().cross((vertices.row(c) - vertices.row(a)).transpose());
    normals.row(a) += n.transpose();
    normals.row(b) += n.transpose();
    normals.row(c) += n.transpose();
  }
  for (int v = 0; v < normals.rows(); ++v) {
    const double length = normals.row(v).norm();
    if (length > 0.0) normals.row(v) /= length;
  }
  return normals;
}

}  // namespace

void MeshRendererOptions::Check() const {
  context.Check();
  const std::string owner = "MeshRendererOptions.";
  RequireOption(near_m > 0.0, owner + "near_m", near_m, "> 0");
  RequireOptions(far_m > near_m && std::isfinite(far_m), owner + "near_m", near_m, owner + "far_m", far_m,
                 "near_m < far_m < infinity");
  RequireOption(max_undistorted_scale >= 1.0 && max_undistorted_scale <= 8.0, owner + "max_undistorted_scale",
                max_undistorted_scale, "in [1, 8]");
  RequireOption(distortion_supersampling >= 1 && distortion_supersampling <= 4, owner + "distortion_supersampling",
                distortion_supersampling, "in [1, 4]");
}

void ShadingOptions::Check() const {
  const std::string owner = "ShadingOptions.";
  const Eigen::Vector3d& light = light_direction_in_world;
  RequireOption(light.allFinite() && light.norm() != 0.0, owner + "light_direction_in_world",
                {light.x(), light.y(), light.z()}, "a finite non-zero vector");
  RequireOption(std::isfinite(ambient) && ambient >= 0.0, owner + "ambient", ambient, ">= 0 and finite");
  RequireOption(std::isfinite(diffuse) && diffuse >= 0.0, owner + "diffuse", diffuse, ">= 0 and finite");
  RequireOption(default_albedo.allFinite(), owner + "default_albedo",
                {default_albedo.x(), default_albedo.y(), default_albedo.z()}, "finite");
  RequireOption(background.allFinite(), owner + "background", {background.x(), background.y(), background.z()},
                "finite");
  if (color_type != PixelType::kUInt8 && color_type != PixelType::kFloat32)
    throw UsageError(owner + "color_type = '" +
                     (color_type == PixelType::kUInt16 ? "kUInt16" : std::to_string(static_cast<int>(color_type))) +
                     "': must be kUInt8 or kFloat32");
}

struct MeshRenderer::Impl {
  MeshRendererOptions options;
  EglContext context;
  GLuint color_program = 0;     // all outputs
  GLuint geometry_program = 0;  // depth, ids and mask only (no shading work)
  GLuint remap_program = 0;
  GLuint empty_vertex_array = 0;
  Target direct;  // rasterisation target (ideal pinhole)
  Target remap;   // distortion remap target
  std::vector<GpuMesh> meshes;
  std::vector<DistortionMap> maps;
  unsigned long long clock = 0;
  int max_size = 0;
  int total_faces = 0;
  std::vector<std::uint8_t> readback;  // RGBA staging for the colour readback

  explicit Impl(const MeshRendererOptions& opts) : options(opts), context(opts.context) {
    color_program = LinkProgram(kMeshVertexShader, std::string("#version 430 core\n#define WITH_COLOR\n") +
                                                       kMeshFragmentShader, "mesh");
    geometry_program = LinkProgram(kMeshVertexShader, std::string("#version 430 core\n") + kMeshFragmentShader, "mesh");
    remap_program = LinkProgram(render_internal::kFullScreenTriangleVertexShader, kRemapFragmentShader, "distortion remap");
    glGenVertexArrays(1, &empty_vertex_array);
    GLint max_texture = 0, max_viewport[2] = {0, 0}, max_renderbuffer = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture);
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, max_viewport);
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_renderbuffer);
    max_size = std::min({max_texture, max_viewport[0], max_viewport[1], max_renderbuffer});
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    const GLenum error = glGetError();
    if (error != GL_NO_ERROR) {
      std::ostringstream out;
      out << "OpenGL: renderer setup failed (GL error 0x" << std::hex << error << ")";
      throw RenderContextError(out.str());
    }
  }

  ~Impl() {
    try {
      context.MakeCurrent();
    } catch (...) {
      return;
    }
    for (GpuMesh& mesh : meshes) ReleaseMesh(&mesh);
    for (DistortionMap& map : maps) glDeleteTextures(1, &map.texture);
    direct.Release();
    remap.Release();
    glDeleteVertexArrays(1, &empty_vertex_array);
    glDeleteProgram(color_program);
    glDeleteProgram(geometry_program);
    glDeleteProgram(remap_program);
  }

  static void ReleaseMesh(GpuMesh* mesh) {
    const GLuint buffers[] = {mesh->positions, mesh->normals, mesh->albedos, mesh->uvs, mesh->indices};
    glDeleteBuffers(5, buffers);
    glDeleteVertexArrays(1, &mesh->vertex_array);
    if (mesh->texture) glDeleteTextures(1, &mesh->texture);
  }

  // Uploads positions and normals of `vertices` (mesh order) into `mesh`'s buffers.
  void UploadGeometry(GpuMesh* mesh, const RowMatrixX3d& vertices, bool allocate) {
    const RowMatrixX3d normals = VertexNormals(vertices, mesh->faces);
    const std::size_t floats = static_cast<std::size_t>(mesh->num_vertices) * 3;
    for (int pass = 0; pass < 2; ++pass) {
      const RowMatrixX3d& source = pass == 0 ? vertices : normals;
      mesh->scratch.resize(floats);
      for (int i = 0; i < mesh->num_vertices; ++i) {
        const int v = mesh->gl_to_mesh.empty() ? i : mesh->gl_to_mesh[i];
        for (int k = 0; k < 3; ++k) mesh->scratch[3 * i + k] = static_cast<float>(source(v, k));
      }
      glBindBuffer(GL_ARRAY_BUFFER, pass == 0 ? mesh->positions : mesh->normals);
      if (allocate)
        glBufferData(GL_ARRAY_BUFFER, floats * sizeof(float), mesh->scratch.data(), GL_DYNAMIC_DRAW);
      else
        glBufferSubData(GL_ARRAY_BUFFER, 0, floats * sizeof(float), mesh->scratch.data());
    }
  }

  GLuint UploadTexture(const Image& image, const std::string& name) {
    if (image.channels < 1 || image.channels > 4) throw InputError(name, "texture must have 1 to 4 channels");
    if (image.width > max_size || image.height > max_size)
      throw InputError(name, "texture is larger than the OpenGL limit of " + std::to_string(max_size) + " pixels");
    const std::size_t n = static_cast<std::size_t>(image.width) * image.height;
    GLuint texture = 0;
    glGenTextures(1, &texture);
    glBindTexture(GL_TEXTURE_2D, texture);
    const int levels = 1 + static_cast<int>(std::floor(std::log2(std::max(image.width, image.height))));
    auto channel = [&](std::size_t pixel, int c) -> int {  // which source channel feeds RGBA channel c
      (void)pixel;
      if (c == 3) return image.channels == 4 ? 3 : image.channels == 2 ? 1 : -1;
      return image.channels >= 3 ? c : 0;
    };
    if (image.type == PixelType::kFloat32) {
      std::vector<float> rgba(n * 4, 1.0f);
      const float* src = image.ptr<float>();
      for (std::size_t p = 0; p < n; ++p)
        for (int c = 0; c < 4; ++c) {
          const int s = channel(p, c);
          if (s >= 0) rgba[4 * p + c] = src[p * image.channels + s];
        }
      glTexStorage2D(GL_TEXTURE_2D, levels, GL_RGBA16F, image.width, image.height);
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, image.width, image.height, GL_RGBA, GL_FLOAT, rgba.data());
    } else {
      // 8/16-bit textures are sRGB-encoded: GL decodes them to linear when sampling.
      std::vector<std::uint8_t> rgba(n * 4, 255);
      for (std::size_t p = 0; p < n; ++p)
        for (int c = 0; c < 4; ++c) {
          const int s = channel(p, c);
          if (s < 0) continue;
          const std::size_t i = p * image.channels + s;
          rgba[4 * p + c] = image.type == PixelType::kUInt8 ? image.ptr<std::uint8_t>()[i]
                                                            : static_cast<std::uint8_t>(image.ptr<std::uint16_t>()[i] >> 8);
        }
      glTexStorage2D(GL_TEXTURE_2D, levels, GL_SRGB8_ALPHA8, image.width, image.height);
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, image.width, image.height, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    }
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
    return texture;
  }

  int AddMesh(const Mesh& mesh, const std::string& name, const Image& texture_image) {
    const int n = mesh.num_vertices();
    CheckVertices(mesh.vertices, name);
    CheckFaceIndices(mesh, name);
    if (mesh.colors.rows() != 0 && mesh.colors.rows() != n)
      throw InputError(name, "has " + std::to_string(mesh.colors.rows()) + " vertex colours for " +
                                 std::to_string(n) + " vertices");
    if (mesh.has_colors() && !mesh.colors.allFinite()) throw InputError(name, "vertex colours contain NaN");
    const bool wants_texture = mesh.has_uvs() && (!texture_image.empty() || !mesh.texture_path.empty());
    if (wants_texture) {
      for (int f = 0; f < mesh.num_faces(); ++f)
        for (int k = 0; k < 3; ++k)
          if (mesh.face_uvs(f, k) < 0 || mesh.face_uvs(f, k) >= mesh.uvs.rows())
            throw InputError(name, Where(f, "face") + " has an out-of-range texture coordinate index");
      if (!mesh.uvs.allFinite()) throw InputError(name, "texture coordinates contain NaN");
    }
    context.MakeCurrent();

    GpuMesh gpu;
    gpu.name = name;
    gpu.num_faces = mesh.num_faces();
    gpu.num_mesh_vertices = n;
    gpu.id_offset = total_faces;
    gpu.faces = mesh.faces;
    gpu.has_colors = mesh.has_colors();
    std::vector<std::uint32_t> indices(static_cast<std::size_t>(gpu.num_faces) * 3);
    std::vector<float> uv_data;
    if (wants_texture) {
      // Split vertices by (vertex, uv) pair.
      std::map<std::pair<int, int>, int> corner_index;
      for (int f = 0; f < gpu.num_faces; ++f)
        for (int k = 0; k < 3; ++k) {
          const std::pair<int, int> key(mesh.faces(f, k), mesh.face_uvs(f, k));
          auto [it, inserted] = corner_index.emplace(key, static_cast<int>(gpu.gl_to_mesh.size()));
          if (inserted) {
            gpu.gl_to_mesh.push_back(key.first);
            uv_data.push_back(static_cast<float>(mesh.uvs(key.second, 0)));
            uv_data.push_back(static_cast<float>(mesh.uvs(key.second, 1)));
          }
          indices[3 * f + k] = static_cast<std::uint32_t>(it->second);
        }
      gpu.num_vertices = static_cast<int>(gpu.gl_to_mesh.size());
    } else {
      for (int f = 0; f < gpu.num_faces; ++f)
        for (int k = 0; k < 3; ++k) indices[3 * f + k] = static_cast<std::uint32_t>(mesh.faces(f, k));
      gpu.num_vertices = n;
    }
    if (wants_texture) {
      gpu.texture = UploadTexture(texture_image.empty() ? ReadImage(mesh.texture_path) : texture_image,
                                  texture_image.empty() ? mesh.texture_path : name + " (texture)");
    }

    glGenVertexArrays(1, &gpu.vertex_array);
    glBindVertexArray(gpu.vertex_array);
    GLuint buffers[5];
    glGenBuffers(5, buffers);
    gpu.positions = buffers[0];
    gpu.normals = buffers[1];
    gpu.albedos = buffers[2];
    gpu.uvs = buffers[3];
    gpu.indices = buffers[4];
    UploadGeometry(&gpu, mesh.vertices, /*allocate=*/true);
    glBindBuffer(GL_ARRAY_BUFFER, gpu.positions);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, gpu.normals);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
    glEnableVertexAttribArray(1);
    if (gpu.has_colors) {
      std::vector<float> colors(static_cast<std::size_t>(gpu.num_vertices) * 3);
      for (int i = 0; i < gpu.num_vertices; ++i) {
        const int v = gpu.gl_to_mesh.empty() ? i : gpu.gl_to_mesh[i];
        for (int k = 0; k < 3; ++k) colors[3 * i + k] = mesh.colors(v, k);
      }
      glBindBuffer(GL_ARRAY_BUFFER, gpu.albedos);
      glBufferData(GL_ARRAY_BUFFER, colors.size() * sizeof(float), colors.data(), GL_STATIC_DRAW);
      glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
      glEnableVertexAttribArray(2);
    }
    if (gpu.texture) {
      glBindBuffer(GL_ARRAY_BUFFER, gpu.uvs);
      glBufferData(GL_ARRAY_BUFFER, uv_data.size() * sizeof(float), uv_data.data(), GL_STATIC_DRAW);
      glVertexAttribPointer(3, 2, GL_FLOAT, GL_FALSE, 0, nullptr);
      glEnableVertexAttribArray(3);
    }
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, gpu.indices);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, indices.size() * sizeof(std::uint32_t), indices.data(), GL_STATIC_DRAW);
    glBindVertexArray(0);
    total_faces += gpu.num_faces;
    meshes.push_back(std::move(gpu));
    return static_cast<int>(meshes.size()) - 1;
  }

  const DistortionMap& MapFor(const Camera& camera) {
    ++clock;
    for (DistortionMap& map : maps)
      if (map.Matches(camera)) {
        map.last_used = clock;
        return map;
      }
    DistortionMap map;
    map.width = camera.width;
    map.height = camera.height;
    map.K = camera.K;
    map.dist = camera.dist;
    map.last_used = clock;
    const int w = camera.width, h = camera.height;
    std::vector<float> ideal(static_cast<std::size_t>(w) * h * 2);
    double min_x = 0.0, min_y = 0.0, max_x = w - 1.0, max_y = h - 1.0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Eigen::Vector2d p = camera.UndistortPixel(Eigen::Vector2d(x, y));
        float* out = &ideal[2 * (static_cast<std::size_t>(y) * w + x)];
        if (!p.allFinite()) {
          out[0] = out[1] = -1e9f;
          continue;
        }
        out[0] = static_cast<float>(p.x());
        out[1] = static_cast<float>(p.y());
        min_x = std::min(min_x, p.x());
        min_y = std::min(min_y, p.y());
        max_x = std::max(max_x, p.x());
        max_y = std::max(max_y, p.y());
      }
    // The ideal buffer covers every looked-up pixel plus a margin, within the size limit.
    const double extra = (options.max_undistorted_scale - 1.0) / 2.0;
    min_x = std::max(min_x, -extra * w);
    min_y = std::max(min_y, -extra * h);
    max_x = std::min(max_x, w - 1.0 + extra * w);
    max_y = std::min(max_y, h - 1.0 + extra * h);
    // Ideal buffer pixel (i, j) has its centre at ideal pixel ((i + 0.5) / S - 0.5 + x0, ...).
    const int S = options.distortion_supersampling;
    map.ideal_x0 = static_cast<int>(std::floor(min_x)) - 2;
    map.ideal_y0 = static_cast<int>(std::floor(min_y)) - 2;
    map.ideal_width = std::min(S * (static_cast<int>(std::ceil(max_x)) + 3 - map.ideal_x0), max_size);
    map.ideal_height = std::min(S * (static_cast<int>(std::ceil(max_y)) + 3 - map.ideal_y0), max_size);
    for (std::size_t i = 0; i < ideal.size(); i += 2) {
      ideal[i] = static_cast<float>(S * (ideal[i] - map.ideal_x0 + 0.5) - 0.5);
      ideal[i + 1] = static_cast<float>(S * (ideal[i + 1] - map.ideal_y0 + 0.5) - 0.5);
    }
    glGenTextures(1, &map.texture);
    glBindTexture(GL_TEXTURE_2D, map.texture);
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RG32F, w, h);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RG, GL_FLOAT, ideal.data());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    constexpr std::size_t kMaxMaps = 16;
    if (maps.size() >= kMaxMaps) {
      auto oldest = std::min_element(maps.begin(), maps.end(), [](const DistortionMap& a, const DistortionMap& b) {
        return a.last_used < b.last_used;
      });
      glDeleteTextures(1, &oldest->texture);
      maps.erase(oldest);
    }
    maps.push_back(map);
    return maps.back();
  }

  RenderResult Render(const Camera& camera, const RenderRequest& request) {
    camera.Check();
    request.shading.Check();
    if (camera.width > max_size || camera.height > max_size)
      throw InputError("", "camera " + camera.name + ": image size " + std::to_string(camera.width) + "x" +
                               std::to_string(camera.height) + " exceeds the OpenGL limit of " +
                               std::to_string(max_size) + " pixels");
    std::vector<int> drawn = request.meshes;
    if (drawn.empty())
      for (int i = 0; i < static_cast<int>(meshes.size()); ++i) drawn.push_back(i);
    for (int handle : drawn)
      if (handle < 0 || handle >= static_cast<int>(meshes.size()))
        throw UsageError("MeshRenderer::Render: unknown mesh handle " + std::to_string(handle));
    context.MakeCurrent();
    const ShadingOptions& shading = request.shading;
    const bool float_color = shading.color_type == PixelType::kFloat32;
    const bool distorted = camera.has_distortion();

    // Ideal pinhole camera rendered first: the camera itself, or the enlarged ideal buffer.
    Eigen::Matrix3d ideal_K = camera.K;
    int ideal_width = camera.width, ideal_height = camera.height;
    const DistortionMap* map = nullptr;
    if (distorted) {
      map = &MapFor(camera);
      // Shift the principal point to the buffer origin, then scale by the supersampling.
      const double S = options.distortion_supersampling;
      ideal_K(0, 2) -= map->ideal_x0;
      ideal_K(1, 2) -= map->ideal_y0;
      ideal_K.row(0) *= S;
      ideal_K.row(1) *= S;
      ideal_K(0, 2) += 0.5 * S - 0.5;
      ideal_K(1, 2) += 0.5 * S - 0.5;
      ideal_width = map->ideal_width;
      ideal_height = map->ideal_height;
    }

    // The remap needs the coverage mask of the ideal buffer even when no silhouette is asked for.
    const bool need_mask = request.silhouette || distorted;
    const GLenum draw_buffers[kNumAttachments] = {
        static_cast<GLenum>(request.color ? GL_COLOR_ATTACHMENT0 : GL_NONE),
        static_cast<GLenum>(request.depth ? GL_COLOR_ATTACHMENT1 : GL_NONE),
        static_cast<GLenum>(request.triangle_id ? GL_COLOR_ATTACHMENT2 : GL_NONE),
        static_cast<GLenum>(need_mask ? GL_COLOR_ATTACHMENT3 : GL_NONE)};
    Eigen::Vector4f background(1.0f, 1.0f, 1.0f, 1.0f);
    for (int c = 0; c < 3; ++c)
      background[c] = shading.srgb_output ? EncodeSrgb(shading.background[c])
                                          : static_cast<float>(std::clamp(shading.background[c], 0.0, 1.0));
    auto clear = [&]() {
      const GLfloat zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
      const GLint minus_one[4] = {-1, -1, -1, -1};
      glDrawBuffers(kNumAttachments, draw_buffers);
      // glClearBuffer* index i is the i-th draw buffer slot; NONE slots are ignored.
      if (request.color) glClearBufferfv(GL_COLOR, kColor, background.data());
      if (request.depth) glClearBufferfv(GL_COLOR, kCameraZ, zero);
      if (request.triangle_id) glClearBufferiv(GL_COLOR, kTriangleId, minus_one);
      if (need_mask) glClearBufferfv(GL_COLOR, kMask, zero);
    };

    // Pass 1: rasterise into the ideal pinhole buffer.
    direct.Ensure(ideal_width, ideal_height, float_color, /*want_depth=*/true);
    glViewport(0, 0, ideal_width, ideal_height);
    clear();
    const GLfloat far_depth = 1.0f;
    glClearBufferfv(GL_DEPTH, 0, &far_depth);
    render_internal::SetMeshRasterState(request.cull_back_faces, GL_LESS);

    const Eigen::Matrix4d cam_from_world = CamFromWorld(camera);
    const Eigen::Matrix4d clip_from_world =
        ClipFromCamera(ideal_K, ideal_width, ideal_height, options.near_m, options.far_m) * cam_from_world;
    const GLuint program = request.color ? color_program : geometry_program;
    glUseProgram(program);
    SetMatrix(program, "clip_from_world", clip_from_world);
    SetMatrix(program, "cam_from_world", cam_from_world);
    if (request.color) {
      const Eigen::Vector3f light = shading.light_direction_in_world.normalized().cast<float>();
      const Eigen::Vector3f center = camera.center_in_world().cast<float>();
      glUniform1i(glGetUniformLocation(program, "lit"), shading.lit ? 1 : 0);
      glUniform1i(glGetUniformLocation(program, "headlight"), shading.headlight ? 1 : 0);
      glUniform3fv(glGetUniformLocation(program, "light_direction"), 1, light.data());
      glUniform3fv(glGetUniformLocation(program, "camera_center"), 1, center.data());
      glUniform1f(glGetUniformLocation(program, "ambient"), static_cast<float>(shading.ambient));
      glUniform1f(glGetUniformLocation(program, "diffuse"), static_cast<float>(shading.diffuse));
      glUniform1i(glGetUniformLocation(program, "srgb_output"), shading.srgb_output ? 1 : 0);
      glUniform1i(glGetUniformLocation(program, "albedo_texture"), 0);
    }
    const GLint id_offset_location = glGetUniformLocation(program, "id_offset");
    const GLint use_texture_location = glGetUniformLocation(program, "use_texture");
    for (int handle : drawn) {
      const GpuMesh& mesh = meshes[handle];
      if (mesh.num_faces == 0) continue;
      glBindVertexArray(mesh.vertex_array);
      if (!mesh.has_colors) {
        const Eigen::Vector3f albedo = shading.default_albedo.cast<float>();
        glVertexAttrib3f(2, albedo.x(), albedo.y(), albedo.z());
      }
      if (request.color) {
        glUniform1i(use_texture_location, mesh.texture ? 1 : 0);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, mesh.texture);
      }
      glUniform1i(id_offset_location, mesh.id_offset);
      glDrawElements(GL_TRIANGLES, mesh.num_faces * 3, GL_UNSIGNED_INT, nullptr);
    }
    glBindVertexArray(0);

    // Pass 2 (distortion): remap the ideal buffer into the distorted image.
    if (distorted) {
      remap.Ensure(camera.width, camera.height, float_color, /*want_depth=*/false);
      glViewport(0, 0, camera.width, camera.height);
      glDisable(GL_DEPTH_TEST);
      glDisable(GL_CULL_FACE);  // the full-screen triangle must not be culled (cull_back_faces)
      glDrawBuffers(kNumAttachments, draw_buffers);
      glUseProgram(remap_program);
      const char* samplers[kNumAttachments] = {"ideal_color", "ideal_camera_z", "ideal_triangle_id", "ideal_mask"};
      for (int i = 0; i < kNumAttachments; ++i) {
        glActiveTexture(GL_TEXTURE1 + i);
        glBindTexture(GL_TEXTURE_2D, direct.textures[i]);
        glUniform1i(glGetUniformLocation(remap_program, samplers[i]), 1 + i);
      }
      glActiveTexture(GL_TEXTURE0);
      glBindTexture(GL_TEXTURE_2D, map->texture);
      glUniform1i(glGetUniformLocation(remap_program, "ideal_from_pixel"), 0);
      glUniform2i(glGetUniformLocation(remap_program, "ideal_size"), ideal_width, ideal_height);
      glUniform4fv(glGetUniformLocation(remap_program, "background"), 1, background.data());
      glBindVertexArray(empty_vertex_array);
      glDrawArrays(GL_TRIANGLES, 0, 3);
      glBindVertexArray(0);
    }

    // Read back (rows come out top first thanks to the flipped projection).
    RenderResult result;
    const int w = camera.width, h = camera.height;
    auto read = [&](Attachment attachment, GLenum format, GLenum type, void* data) {
      glReadBuffer(GL_COLOR_ATTACHMENT0 + attachment);
      glReadPixels(0, 0, w, h, format, type, data);
    };
    if (request.color) {
      // RGBA is the driver's fast readback path (no per-pixel format conversion); drop alpha here.
      result.color = Image(w, h, 3, shading.color_type);
      const std::size_t pixels = static_cast<std::size_t>(w) * h;
      const std::size_t value_bytes = BytesPerChannel(shading.color_type);
      readback.resize(pixels * 4 * value_bytes);
      read(kColor, GL_RGBA, float_color ? GL_FLOAT : GL_UNSIGNED_BYTE, readback.data());
      std::uint8_t* out = result.color.data.data();
      for (std::size_t i = 0; i < pixels; ++i)
        std::memcpy(out + 3 * value_bytes * i, readback.data() + 4 * value_bytes * i, 3 * value_bytes);
    }
    if (request.depth) {
      result.depth = Image(w, h, 1, PixelType::kFloat32);
      read(kCameraZ, GL_RED, GL_FLOAT, result.depth.data.data());
    }
    if (request.silhouette) {
      result.silhouette = Image(w, h, 1, PixelType::kUInt8);
      read(kMask, GL_RED, GL_UNSIGNED_BYTE, result.silhouette.data.data());
    }
    if (request.triangle_id) {
      result.triangle_id.width = w;
      result.triangle_id.height = h;
      result.triangle_id.ids.resize(static_cast<std::size_t>(w) * h);
      read(kTriangleId, GL_RED_INTEGER, GL_INT, result.triangle_id.ids.data());
    }
    const GLenum error = glGetError();
    if (error != GL_NO_ERROR) {
      std::ostringstream out;
      out << "OpenGL: rendering camera " << camera.name << " failed (GL error 0x" << std::hex << error << ")";
      throw RenderContextError(out.str());
    }
    return result;
  }
};

MeshRenderer::MeshRenderer(const MeshRendererOptions& options) {
  options.Check();
  impl_ = std::make_unique<Impl>(options);
}

MeshRenderer::~MeshRenderer() = default;

int MeshRenderer::AddMesh(const Mesh& mesh, const std::string& name, const Image& texture) {
  return impl_->AddMesh(mesh, name, texture);
}

void MeshRenderer::UpdateVertices(int handle, const RowMatrixX3d& vertices) {
  if (handle < 0 || handle >= num_meshes())
    throw UsageError("MeshRenderer::UpdateVertices: unknown mesh handle " + std::to_string(handle));
  GpuMesh& mesh = impl_->meshes[handle];
  if (vertices.rows() != mesh.num_mesh_vertices)
    throw InputError(mesh.name, "got " + std::to_string(vertices.rows()) + " vertices for a mesh uploaded with " +
                                    std::to_string(mesh.num_mesh_vertices));
  CheckVertices(vertices, mesh.name);
  impl_->context.MakeCurrent();
  impl_->UploadGeometry(&mesh, vertices, /*allocate=*/false);
}

int MeshRenderer::num_meshes() const { return static_cast<int>(impl_->meshes.size()); }

int MeshRenderer::id_offset(int handle) const {
  if (handle < 0 || handle >= num_meshes())
    throw UsageError("MeshRenderer::id_offset: unknown mesh handle " + std::to_string(handle));
  return impl_->meshes[handle].id_offset;
}

RenderResult MeshRenderer::Render(const Camera& camera, const RenderRequest& request) {
  return impl_->Render(camera, request);
}

const EglContextInfo& MeshRenderer::context_info() const { return impl_->context.info(); }

}  // namespace confluent
