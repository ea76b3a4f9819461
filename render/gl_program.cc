#include "render/gl_program.h"

#include <sstream>

#include "core/error.h"
#include "render/egl_context.h"

namespace confluent::render_internal {
namespace {

GLuint CompileShader(GLenum type, const std::string& source, const std::string& what) {
  const GLuint shader = glCreateShader(type);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096] = {0};
    glGetShaderInfoLog(shader, sizeof(log) - 1, nullptr, log);
    glDeleteShader(shader);
    throw RenderContextError("OpenGL: " + what + " shader does not compile: " + log);
  }
  return shader;
}

}  // namespace

GLuint LinkProgram(const std::string& vertex_source, const std::string& fragment_source, const std::string& what) {
  const GLuint vertex = CompileShader(GL_VERTEX_SHADER, vertex_source, what);
  const GLuint fragment = CompileShader(GL_FRAGMENT_SHADER, fragment_source, what);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vertex);
  glAttachShader(program, fragment);
  glLinkProgram(program);
  glDeleteShader(vertex);
  glDeleteShader(fragment);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096] = {0};
    glGetProgramInfoLog(program, sizeof(log) - 1, nullptr, log);
    glDeleteProgram(program);
    throw RenderContextError("OpenGL: " + what + " shader program does not link: " + log);
  }
  return program;
}

Eigen::Matrix4d ClipFromCamera(const Eigen::Matrix3d& K, int width, int height, double near_m, double far_m,
                               bool flip_y) {
  const double n = near_m, f = far_m;
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  P(0, 0) = 2.0 * K(0, 0) / width;
  P(0, 1) = 2.0 * K(0, 1) / width;
  P(0, 2) = 2.0 * (K(0, 2) + 0.5) / width - 1.0;
  P(1, 1) = 2.0 * K(1, 1) / height;
  P(1, 2) = 2.0 * (K(1, 2) + 0.5) / height - 1.0;
  if (!flip_y) {
    P(1, 1) = -P(1, 1);
    P(1, 2) = -P(1, 2);
  }
  P(2, 2) = (f + n) / (f - n);
  P(2, 3) = -2.0 * f * n / (f - n);
  P(3, 2) = 1.0;
  return P;
}

void SetMeshRasterState(bool cull_back_faces, GLenum depth_func) {
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(depth_func);
  if (cull_back_faces) {
    glEnable(GL_CULL_FACE);
    glFrontFace(GL_CW);
    glCullFace(GL_BACK);
  } else {
    glDisable(GL_CULL_FACE);
  }
  glDisable(GL_BLEND);
}

Eigen::Matrix4d CamFromWorld(const Camera& camera) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = camera.rotation;
  m.topRightCorner<3, 1>() = camera.translation;
  return m;
}

void CheckVertices(const RowMatrixX3d& vertices, const std::string& name) {
  for (int v = 0; v < vertices.rows(); ++v)
    if (!vertices.row(v).allFinite()) {
      std::ostringstream out;
      out << "vertex " << v << " has a non-finite coordinate (" << vertices(v, 0) << ", " << vertices(v, 1) << ", "
          << vertices(v, 2) << ")";
      throw InputError(name, out.str());
    }
}

void CheckFaceIndices(const Mesh& mesh, const std::string& name) {
  const int n = mesh.num_vertices();
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh.faces(f, k) < 0 || mesh.faces(f, k) >= n) {
        std::ostringstream out;
        out << "face " << f << " refers to vertex " << mesh.faces(f, k) << ", but the mesh has " << n << " vertices";
        throw InputError(name, out.str());
      }
}

}  // namespace confluent::render_internal
