#pragma once
// INTERNAL (render/renderer.cc only): the GL resources MeshRenderer holds: offscreen render
// targets, uploaded meshes, and per-camera distortion remaps.

#include <epoxy/gl.h>

#include <Eigen/Core>
#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "core/mesh.h"
#include "render/egl_context.h"
#include "render/renderer_shaders.h"

namespace confluent::mesh_renderer_internal {

// Offscreen framebuffer with the four colour attachments (textures) and optionally a depth
// buffer. Storage only grows; a render uses the lower-left width x height region.
struct Target {
  GLuint framebuffer = 0;
  GLuint textures[kNumAttachments] = {0, 0, 0, 0};
  GLuint depth_buffer = 0;
  int width = 0;   // allocated size
  int height = 0;
  bool float_color = false;
  bool with_depth = false;

  void Release() {
    if (framebuffer) glDeleteFramebuffers(1, &framebuffer);
    glDeleteTextures(kNumAttachments, textures);
    if (depth_buffer) glDeleteRenderbuffers(1, &depth_buffer);
    framebuffer = depth_buffer = 0;
    for (GLuint& t : textures) t = 0;
    width = height = 0;
  }

  // Makes the target at least `w` x `h` with the given colour format, and binds it.
  void Ensure(int w, int h, bool want_float_color, bool want_depth) {
    if (framebuffer != 0 && w <= width && h <= height && want_float_color == float_color) {
      glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
      return;
    }
    const int new_width = std::max(w, width), new_height = std::max(h, height);
    Release();
    width = new_width;
    height = new_height;
    float_color = want_float_color;
    with_depth = want_depth;
    glGenFramebuffers(1, &framebuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glGenTextures(kNumAttachments, textures);
    const GLenum formats[kNumAttachments] = {static_cast<GLenum>(float_color ? GL_RGBA32F : GL_RGBA8), GL_R32F,
                                             GL_R32I, GL_R8};
    for (int i = 0; i < kNumAttachments; ++i) {
      glBindTexture(GL_TEXTURE_2D, textures[i]);
      glTexStorage2D(GL_TEXTURE_2D, 1, formats[i], width, height);
      const GLint filter = i == kColor ? GL_LINEAR : GL_NEAREST;
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D, textures[i], 0);
    }
    if (with_depth) {
      glGenRenderbuffers(1, &depth_buffer);
      glBindRenderbuffer(GL_RENDERBUFFER, depth_buffer);
      glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_buffer);
    }
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      std::ostringstream out;
      out << "OpenGL: offscreen framebuffer " << width << "x" << height << " is incomplete (status 0x" << std::hex
          << status << ")";
      throw RenderContextError(out.str());
    }
  }
};

// One uploaded mesh. GL vertices are the distinct (vertex, uv) corners; gl_to_mesh maps them
// back to mesh vertices so that per-frame updates only gather positions and normals.
struct GpuMesh {
  std::string name;
  GLuint vertex_array = 0;
  GLuint positions = 0, normals = 0, albedos = 0, uvs = 0, indices = 0;
  GLuint texture = 0;
  int num_vertices = 0;       // GL vertices
  int num_mesh_vertices = 0;  // vertices of the uploaded Mesh
  int num_faces = 0;
  int id_offset = 0;
  bool has_colors = false;
  RowMatrixX3i faces;            // mesh faces (mesh vertex indices), for normals
  std::vector<int> gl_to_mesh;   // empty = identity
  std::vector<float> scratch;    // upload staging
};

// Distortion remap of one camera: the ideal buffer's placement and the per-pixel map.
struct DistortionMap {
  int width = 0, height = 0;
  Eigen::Matrix3d K;
  Vector5d dist;
  int ideal_x0 = 0, ideal_y0 = 0;  // ideal pixel of the ideal buffer's pixel (0, 0)
  int ideal_width = 0, ideal_height = 0;
  GLuint texture = 0;  // RG32F, width x height
  unsigned long long last_used = 0;

  bool Matches(const Camera& camera) const {
    return camera.width == width && camera.height == height && camera.K == K && camera.dist == dist;
  }
};

}  // namespace confluent::mesh_renderer_internal
