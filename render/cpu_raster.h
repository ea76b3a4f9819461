#pragma once
// A small z-buffer rasteriser of triangle meshes on the CPU, for pinhole cameras (the projective
// texturer's depth maps and G-buffer on a software GL such as llvmpipe, where the per-triangle
// setup of the GL pipeline dominates: a ~20K-face depth map costs a few milliseconds here).
//
// Conventions match MeshRenderer (render/renderer.h) and ClipFromCamera: pixel centres at integer
// OpenCV coordinates, rows top first, faces counter-clockwise seen from outside are front faces.
// Coverage: a pixel centre inside the triangle, with a top-left rule on the edges (8 sub-pixel
// bits), so that a closed mesh covers every pixel once. Depth: 1 / camera z is interpolated
// linearly in the image (perspective-correct, as GL's window depth); the nearest face wins.
// Triangles are clipped at the near plane and at a guard band around the image; surface beyond
// the far plane is not drawn. Lens distortion is ignored (draw ideal pixels and remap, or use GL).

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "calib/camera.h"
#include "core/mesh.h"

namespace confluent {

// Options of CpuRasterizer.
struct CpuRasterOptions {
  double near_m = 0.01;          // near clipping plane (camera z), metres
  double far_m = 100.0;          // surface farther than this (camera z, metres) is not drawn
  bool cull_back_faces = true;   // skip faces seen from behind (clockwise in the image)
  // Throws UsageError when a value is out of range (0 < near_m < far_m, finite).
  void Check() const;
};

// Pixels [x0, x1) x [y0, y1) of an image; empty when x1 <= x0 or y1 <= y0.
struct PixelBox {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  // The smallest box holding both (an empty box adds nothing).
  PixelBox Union(const PixelBox& other) const {
    if (other.empty()) return *this;
    if (empty()) return other;
    return PixelBox{std::min(x0, other.x0), std::min(y0, other.y0), std::max(x1, other.x1), std::max(y1, other.y1)};
  }
};

// Sets the pixels of `box` in a row-major buffer `width` pixels wide, `channels` values per pixel,
// to `value` (clearing only what a previous frame wrote).
template <typename T>
void FillBox(T* data, int width, const PixelBox& box, T value, int channels = 1) {
  for (int y = box.y0; y < box.y1; ++y) {
    T* row = data + (static_cast<std::size_t>(y) * width) * channels;
    std::fill(row + box.x0 * channels, row + box.x1 * channels, value);
  }
}

// The mesh's vertices projected into one camera (CpuRasterizer::Project), the input of Draw.
struct CpuRasterFrame {
  int width = 0, height = 0;  // the camera's image size
  double fx = 0, fy = 0, cx = 0, cy = 0, skew = 0;
  struct Vertex {
    float x = 0, y = 0, z = 0;   // camera frame, metres
    std::int32_t u = 0, v = 0;   // pixel position in 1/256 pixel (valid only when `fast`)
    float pixel_u = 0, pixel_v = 0;  // pixel position, unrounded (for the depth interpolation)
    float inverse_z = 0;         // 1 / z
    bool fast = false;           // in front of the near plane and inside the guard band
  };
  std::vector<Vertex> vertices;  // per vertex the rasteriser uses (its own compact numbering)
};

// Rasterises a fixed set of faces (the topology lives across frames; the vertices change per frame).
// Project and Draw are const and thread-safe: several threads may draw the same frame into
// disjoint row ranges, or different cameras.
class CpuRasterizer {
 public:
  // `faces` index vertices 0..num_vertices-1 of the vertex arrays later given to Project; only the
  // vertices the faces use are projected. Throws InputError("mesh") for an index out of range and
  // UsageError for bad options.
  CpuRasterizer(const RowMatrixX3i& faces, int num_vertices, const CpuRasterOptions& options = {});

  // Projects `vertices_in_world` (num_vertices x 3, metres) into `camera` (pinhole: K, rotation,
  // translation and size; distortion ignored) into *frame.
  void Project(const Camera& camera, const RowMatrixX3f& vertices_in_world, CpuRasterFrame* frame) const;

  // Draws the faces into rows [row_begin, row_end) of the frame's image: per pixel (row-major,
  // width x height buffers) `inverse_depth` keeps the largest 1 / camera z (the nearest surface;
  // the caller clears it to 0) and, when `face_ids` is not null, that surface's face index (an
  // index into the constructor's `faces`). Returns a box containing every pixel written (may be
  // larger).
  PixelBox Draw(const CpuRasterFrame& frame, int row_begin, int row_end, float* inverse_depth,
                std::int32_t* face_ids = nullptr) const;

  // Depth maps: `camera_z` (width x height) gets the camera z of the nearest surface per pixel, 0
  // where none; `frame` is scratch. Returns the box of covered pixels (possibly larger). With
  // `previous` (the box this call returned for the same buffer last time) only that box is
  // cleared, when the buffer already has the camera's size; without, the whole buffer is.
  PixelBox DrawDepth(const Camera& camera, const RowMatrixX3f& vertices_in_world, CpuRasterFrame* frame,
                     std::vector<float>* camera_z, const PixelBox* previous = nullptr) const;

  int num_faces() const { return static_cast<int>(faces_.size()); }

 private:
  CpuRasterOptions options_;
  std::vector<std::int32_t> used_vertices_;     // compact index -> mesh vertex
  std::vector<std::array<std::int32_t, 3>> faces_;  // compact vertex indices
};

}  // namespace confluent
