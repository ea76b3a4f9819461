#include "render/viewer_scene.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/error.h"
#include "core/mesh_ops.h"
#include "render/egl_context.h"
#include "render/gl_program.h"

namespace confluent {
namespace {

using render_internal::LinkProgram;

constexpr const char* kMeshVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 color;
uniform mat4 cam_from_world;
uniform mat4 projection;
out vec3 v_position_in_cam;
out vec3 v_normal_in_cam;
out vec3 v_color;
void main() {
  vec4 p = cam_from_world * vec4(position, 1.0);
  v_position_in_cam = p.xyz;
  v_normal_in_cam = mat3(cam_from_world) * normal;
  v_color = color;
  gl_Position = projection * p;
}
)";

// mode 0: lit (two-sided headlight), 1: unlit vertex colour, 2: uniform colour.
constexpr const char* kMeshFragmentShader = R"(#version 330 core
in vec3 v_position_in_cam;
in vec3 v_normal_in_cam;
in vec3 v_color;
uniform int mode;
uniform float ambient;
uniform float diffuse;
uniform vec3 uniform_color;
out vec4 frag_color;
void main() {
  vec3 c = v_color;
  if (mode == 0) {
    float lambert = 1.0;
    float len = length(v_normal_in_cam);
    if (len > 0.0) lambert = abs(dot(v_normal_in_cam / len, normalize(-v_position_in_cam)));
    c = v_color * (ambient + diffuse * lambert);
  } else if (mode == 2) {
    c = uniform_color;
  }
  frag_color = vec4(clamp(c, 0.0, 1.0), 1.0);
}
)";

constexpr const char* kImageVertexShader = R"(#version 330 core
out vec2 v_uv;
void main() {
  vec2 corner = vec2(float(gl_VertexID & 1), float((gl_VertexID >> 1) & 1));
  vec2 ndc = corner * 2.0 - 1.0;
  v_uv = vec2(corner.x, 1.0 - corner.y);  // image rows are top first
  gl_Position = vec4(ndc, 0.0, 1.0);
}
)";

constexpr const char* kImageFragmentShader = R"(#version 330 core
in vec2 v_uv;
uniform sampler2D image;
out vec4 frag_color;
void main() { frag_color = vec4(texture(image, v_uv).rgb, 1.0); }
)";

constexpr const char* kRectVertexShader = R"(#version 330 core
layout(location = 0) in vec2 pixel;
layout(location = 1) in vec4 color;
uniform vec2 viewport;
out vec4 v_color;
void main() {
  v_color = color;
  gl_Position = vec4(2.0 * pixel.x / viewport.x - 1.0, 1.0 - 2.0 * pixel.y / viewport.y, 0.0, 1.0);
}
)";

constexpr const char* kRectFragmentShader = R"(#version 330 core
in vec4 v_color;
out vec4 frag_color;
void main() { frag_color = v_color; }
)";

// cam_from_world as a column-major 4x4.
Eigen::Matrix4f ViewMatrix(const Camera& view) { return render_internal::CamFromWorld(view).cast<float>(); }

// OpenCV K -> GL clip space for the window (image row 0 at the top of the window).
Eigen::Matrix4f ProjectionMatrix(const Camera& view, double near_m, double far_m) {
  return render_internal::ClipFromCamera(view.K, view.width, view.height, near_m, far_m, /*flip_y=*/false).cast<float>();
}

}  // namespace

struct ViewerScene::Impl {
  GLuint mesh_program = 0;
  GLuint image_program = 0;
  GLuint rect_program = 0;

  GLuint mesh_vao = 0;
  GLuint mesh_buffers[4] = {0, 0, 0, 0};  // positions, normals, colours, indices
  GLsizei mesh_index_count = 0;
  int mesh_vertex_count = 0;
  RowMatrixX3f mesh_own_colors;  // colours used when no override is given

  GLuint line_vao = 0;
  GLuint line_buffers[2] = {0, 0};  // positions, colours
  GLsizei line_vertex_count = 0;

  GLuint image_vao = 0;
  GLuint image_texture = 0;
  bool has_image = false;

  GLuint rect_vao = 0;
  GLuint rect_buffer = 0;

  void UploadColors(const RowMatrixX3f& colors) {
    glBindBuffer(GL_ARRAY_BUFFER, mesh_buffers[2]);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(colors.size() * sizeof(float)), colors.data(),
                 GL_DYNAMIC_DRAW);
  }

  void SetCameraUniforms(const Camera& view, const ViewerMeshOptions& options) {
    const Eigen::Matrix4f view_matrix = ViewMatrix(view);
    const Eigen::Matrix4f projection = ProjectionMatrix(view, options.near_m, options.far_m);
    glUseProgram(mesh_program);
    glUniformMatrix4fv(glGetUniformLocation(mesh_program, "cam_from_world"), 1, GL_FALSE, view_matrix.data());
    glUniformMatrix4fv(glGetUniformLocation(mesh_program, "projection"), 1, GL_FALSE, projection.data());
    glUniform1f(glGetUniformLocation(mesh_program, "ambient"), static_cast<float>(options.ambient));
    glUniform1f(glGetUniformLocation(mesh_program, "diffuse"), static_cast<float>(options.diffuse));
  }
};

ViewerScene::ViewerScene() : impl_(std::make_unique<Impl>()) {
  const GLubyte* version = glGetString(GL_VERSION);
  if (version == nullptr) throw RenderContextError("viewer: no current OpenGL context");
  if (epoxy_gl_version() < 33 || epoxy_is_desktop_gl() == 0)
    throw RenderContextError(std::string("viewer: needs desktop OpenGL >= 3.3, the context has ") +
                             reinterpret_cast<const char*>(version));
  impl_->mesh_program = LinkProgram(kMeshVertexShader, kMeshFragmentShader, "viewer mesh");
  impl_->image_program = LinkProgram(kImageVertexShader, kImageFragmentShader, "viewer image");
  impl_->rect_program = LinkProgram(kRectVertexShader, kRectFragmentShader, "viewer overlay");

  glGenVertexArrays(1, &impl_->mesh_vao);
  glGenBuffers(4, impl_->mesh_buffers);
  glBindVertexArray(impl_->mesh_vao);
  for (GLuint attribute = 0; attribute < 3; ++attribute) {
    glBindBuffer(GL_ARRAY_BUFFER, impl_->mesh_buffers[attribute]);
    glEnableVertexAttribArray(attribute);
    glVertexAttribPointer(attribute, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  }
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, impl_->mesh_buffers[3]);

  glGenVertexArrays(1, &impl_->line_vao);
  glGenBuffers(2, impl_->line_buffers);
  glBindVertexArray(impl_->line_vao);
  glBindBuffer(GL_ARRAY_BUFFER, impl_->line_buffers[0]);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  glVertexAttrib3f(1, 0.0f, 0.0f, 0.0f);  // no normal: drawn unlit
  glBindBuffer(GL_ARRAY_BUFFER, impl_->line_buffers[1]);
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 3, GL_FLOAT, GL_FALSE, 0, nullptr);

  glGenVertexArrays(1, &impl_->image_vao);
  glGenTextures(1, &impl_->image_texture);
  glBindTexture(GL_TEXTURE_2D, impl_->image_texture);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);

  glGenVertexArrays(1, &impl_->rect_vao);
  glGenBuffers(1, &impl_->rect_buffer);
  glBindVertexArray(impl_->rect_vao);
  glBindBuffer(GL_ARRAY_BUFFER, impl_->rect_buffer);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_FLOAT, GL_FALSE, 6 * sizeof(float), reinterpret_cast<void*>(2 * sizeof(float)));
  glBindVertexArray(0);
}

ViewerScene::~ViewerScene() {
  if (glGetString(GL_VERSION) == nullptr) return;  // the context is gone: nothing to free
  glDeleteBuffers(4, impl_->mesh_buffers);
  glDeleteBuffers(2, impl_->line_buffers);
  glDeleteBuffers(1, &impl_->rect_buffer);
  const GLuint vaos[4] = {impl_->mesh_vao, impl_->line_vao, impl_->image_vao, impl_->rect_vao};
  glDeleteVertexArrays(4, vaos);
  glDeleteTextures(1, &impl_->image_texture);
  glDeleteProgram(impl_->mesh_program);
  glDeleteProgram(impl_->image_program);
  glDeleteProgram(impl_->rect_program);
}

void ViewerScene::SetMesh(const Mesh& mesh, const RowMatrixX3f& colors) {
  const int n = mesh.num_vertices();
  if (!mesh.vertices.allFinite()) throw InputError("mesh", "non-finite vertex coordinates");
  if (mesh.num_faces() > 0 && (mesh.faces.minCoeff() < 0 || mesh.faces.maxCoeff() >= n))
    throw InputError("mesh", "face index out of range");
  const RowMatrixX3f positions = mesh.vertices.cast<float>();
  const RowMatrixX3f normals = VertexNormals(mesh).cast<float>();
  if (mesh.has_colors()) {
    impl_->mesh_own_colors = mesh.colors;
  } else {
    impl_->mesh_own_colors.resize(0, 3);
  }
  impl_->mesh_vertex_count = n;
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, impl_->mesh_buffers[0]);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(positions.size() * sizeof(float)), positions.data(),
               GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, impl_->mesh_buffers[1]);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(normals.size() * sizeof(float)), normals.data(),
               GL_DYNAMIC_DRAW);
  const Eigen::Matrix<std::uint32_t, Eigen::Dynamic, 3, Eigen::RowMajor> indices = mesh.faces.cast<std::uint32_t>();
  glBindVertexArray(impl_->mesh_vao);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, impl_->mesh_buffers[3]);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)),
               indices.data(), GL_DYNAMIC_DRAW);
  glBindVertexArray(0);
  impl_->mesh_index_count = static_cast<GLsizei>(indices.size());
  SetMeshColors(colors.rows() == n && n > 0 ? colors : RowMatrixX3f());
}

void ViewerScene::SetMeshColors(const RowMatrixX3f& colors) {
  const int n = impl_->mesh_vertex_count;
  if (colors.rows() != 0 && colors.rows() != n)
    throw UsageError("ViewerScene::SetMeshColors: " + std::to_string(colors.rows()) + " colours for " +
                     std::to_string(n) + " vertices");
  if (colors.rows() == n && n > 0) {
    impl_->UploadColors(colors);
  } else if (impl_->mesh_own_colors.rows() == n && n > 0) {
    impl_->UploadColors(impl_->mesh_own_colors);
  } else {
    const ViewerMeshOptions defaults;
    RowMatrixX3f grey(n, 3);
    grey.rowwise() = defaults.default_albedo.cast<float>().transpose();
    impl_->UploadColors(grey);
  }
}

bool ViewerScene::has_mesh() const { return impl_->mesh_index_count > 0; }

void ViewerScene::SetLines(const std::vector<ViewerLine>& lines) {
  RowMatrixX3f positions(2 * lines.size(), 3), colors(2 * lines.size(), 3);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    positions.row(2 * i) = lines[i].from_in_world.cast<float>().transpose();
    positions.row(2 * i + 1) = lines[i].to_in_world.cast<float>().transpose();
    colors.row(2 * i) = colors.row(2 * i + 1) = lines[i].color.cast<float>().transpose();
  }
  glBindBuffer(GL_ARRAY_BUFFER, impl_->line_buffers[0]);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(positions.size() * sizeof(float)), positions.data(),
               GL_DYNAMIC_DRAW);
  glBindBuffer(GL_ARRAY_BUFFER, impl_->line_buffers[1]);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(colors.size() * sizeof(float)), colors.data(),
               GL_DYNAMIC_DRAW);
  impl_->line_vertex_count = static_cast<GLsizei>(positions.rows());
}

void ViewerScene::SetImage(const Image& image) {
  impl_->has_image = !image.empty();
  if (!impl_->has_image) return;
  if (image.type != PixelType::kUInt8 || image.channels < 1 || image.channels > 4)
    throw UsageError("ViewerScene::SetImage: expected an 8-bit image with 1 to 4 channels");
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(image.width) * image.height * 4, 255);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      std::uint8_t* out = &rgba[(static_cast<std::size_t>(y) * image.width + x) * 4];
      for (int c = 0; c < 3; ++c) out[c] = image.at<std::uint8_t>(x, y, image.channels >= 3 ? c : 0);
    }
  glBindTexture(GL_TEXTURE_2D, impl_->image_texture);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, image.width, image.height, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
}

void ViewerScene::Clear(int width_px, int height_px, const Eigen::Vector3d& background) {
  glViewport(0, 0, width_px, height_px);
  glClearColor(static_cast<float>(background.x()), static_cast<float>(background.y()),
               static_cast<float>(background.z()), 1.0f);
  glClearDepth(1.0);
  glDepthMask(GL_TRUE);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

void ViewerScene::DrawImage() {
  if (!impl_->has_image) return;
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glUseProgram(impl_->image_program);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, impl_->image_texture);
  glUniform1i(glGetUniformLocation(impl_->image_program, "image"), 0);
  glBindVertexArray(impl_->image_vao);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  glBindVertexArray(0);
}

void ViewerScene::DrawMesh(const Camera& view, const ViewerMeshOptions& options) {
  if (impl_->mesh_index_count == 0) return;
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  impl_->SetCameraUniforms(view, options);
  const GLuint program = impl_->mesh_program;
  glBindVertexArray(impl_->mesh_vao);
  if (options.style == ViewerMeshStyle::kWireframe) {
    // Depth-only pass pushed back a little, then the edges: hidden lines are removed.
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.0f, 1.0f);
    glDrawElements(GL_TRIANGLES, impl_->mesh_index_count, GL_UNSIGNED_INT, nullptr);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glUniform1i(glGetUniformLocation(program, "mode"), 2);
    glUniform3f(glGetUniformLocation(program, "uniform_color"), static_cast<float>(options.wire_color.x()),
                static_cast<float>(options.wire_color.y()), static_cast<float>(options.wire_color.z()));
    glDepthFunc(GL_LEQUAL);
    glPolygonMode(GL_FRONT_AND_BACK, GL_LINE);
    glDrawElements(GL_TRIANGLES, impl_->mesh_index_count, GL_UNSIGNED_INT, nullptr);
    glPolygonMode(GL_FRONT_AND_BACK, GL_FILL);
    glDepthFunc(GL_LESS);
  } else {
    glUniform1i(glGetUniformLocation(program, "mode"), options.style == ViewerMeshStyle::kShaded ? 0 : 1);
    glDrawElements(GL_TRIANGLES, impl_->mesh_index_count, GL_UNSIGNED_INT, nullptr);
  }
  glBindVertexArray(0);
}

void ViewerScene::DrawLines(const Camera& view, const ViewerMeshOptions& options) {
  if (impl_->line_vertex_count == 0) return;
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDisable(GL_BLEND);
  impl_->SetCameraUniforms(view, options);
  glUniform1i(glGetUniformLocation(impl_->mesh_program, "mode"), 1);
  glBindVertexArray(impl_->line_vao);
  glDrawArrays(GL_LINES, 0, impl_->line_vertex_count);
  glBindVertexArray(0);
  glDepthFunc(GL_LESS);
}

void ViewerScene::DrawRects(const std::vector<ViewerRect>& rects, int width_px, int height_px) {
  if (rects.empty()) return;
  std::vector<float> vertices;
  vertices.reserve(rects.size() * 6 * 6);
  for (const ViewerRect& rect : rects) {
    const float xs[6] = {float(rect.x0), float(rect.x1), float(rect.x1), float(rect.x0), float(rect.x1), float(rect.x0)};
    const float ys[6] = {float(rect.y0), float(rect.y0), float(rect.y1), float(rect.y0), float(rect.y1), float(rect.y1)};
    for (int i = 0; i < 6; ++i) {
      vertices.insert(vertices.end(), {xs[i], ys[i]});
      for (int c = 0; c < 4; ++c) vertices.push_back(static_cast<float>(rect.color[c]));
    }
  }
  glViewport(0, 0, width_px, height_px);
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUseProgram(impl_->rect_program);
  glUniform2f(glGetUniformLocation(impl_->rect_program, "viewport"), static_cast<float>(width_px),
              static_cast<float>(height_px));
  glBindVertexArray(impl_->rect_vao);
  glBindBuffer(GL_ARRAY_BUFFER, impl_->rect_buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)), vertices.data(),
               GL_STREAM_DRAW);
  glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(vertices.size() / 6));
  glBindVertexArray(0);
  glDisable(GL_BLEND);
}

Image ViewerScene::ReadPixels(int width_px, int height_px) const {
  Image image(width_px, height_px, 3);
  std::vector<std::uint8_t> rows(image.data.size());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glFinish();
  glReadPixels(0, 0, width_px, height_px, GL_RGB, GL_UNSIGNED_BYTE, rows.data());
  const std::size_t row_bytes = image.row_bytes();
  for (int y = 0; y < height_px; ++y)  // GL rows are bottom first
    std::copy_n(&rows[static_cast<std::size_t>(height_px - 1 - y) * row_bytes], row_bytes,
                &image.data[static_cast<std::size_t>(y) * row_bytes]);
  return image;
}

void ReleaseCurrentEglContext() {
  const EGLContext context = eglGetCurrentContext();
  if (context == EGL_NO_CONTEXT) return;
  const EGLDisplay display = eglGetCurrentDisplay();
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
}

}  // namespace confluent
