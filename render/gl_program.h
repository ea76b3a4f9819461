#pragma once
// INTERNAL (render/*.cc only): GL helpers shared by the renderer, the projective texturer and
// the viewer: shader programs, and the projection that makes a GL render match an OpenCV camera.

#include <epoxy/gl.h>

#include <Eigen/Core>
#include <string>

#include "calib/camera.h"
#include "core/mesh.h"

namespace confluent::render_internal {

// A vertex shader that covers the viewport with one triangle (draw 3 vertices, no buffers).
constexpr const char* kFullScreenTriangleVertexShader = R"(#version 430 core
void main() {
  vec2 corner = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
)";

// Compiles and links a vertex + fragment shader program. Throws RenderContextError naming
// `what` (e.g. "projective texture") with the GL log when either step fails.
GLuint LinkProgram(const std::string& vertex_source, const std::string& fragment_source, const std::string& what);

// OpenCV K (pixel centres at integers, y down) -> GL clip space for a width x height viewport.
// With `flip_y` (offscreen reads) the y flip is folded in, so that glReadPixels returns rows top
// first; without it (an on-screen window) image row 0 is the top of the window.
Eigen::Matrix4d ClipFromCamera(const Eigen::Matrix3d& K, int width, int height, double near_m, double far_m,
                               bool flip_y = true);

// Depth test on (GL_LESS or GL_LEQUAL in `depth_func`), blending off, and back faces culled
// when `cull_back_faces` (meshes are counter-clockwise seen from outside, which the y flip of
// ClipFromCamera makes clockwise in window coordinates).
void SetMeshRasterState(bool cull_back_faces, GLenum depth_func = GL_LESS);

// Throws InputError(name, ...) naming the first vertex with a non-finite coordinate.
void CheckVertices(const RowMatrixX3d& vertices, const std::string& name);

// Throws InputError(name, ...) naming the first face that refers to a vertex out of range.
void CheckFaceIndices(const Mesh& mesh, const std::string& name);

// The camera's cam_from_world as a 4x4 matrix.
Eigen::Matrix4d CamFromWorld(const Camera& camera);

}  // namespace confluent::render_internal
