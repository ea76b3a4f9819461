// CpuRasterizer: edge functions in 24.8 fixed point (exact, so that shared edges neither leave gaps
// nor draw twice), 1 / z as a plane in the image, a bounding-box scan per triangle (the triangles
// of a depth-map proxy or a scan seen whole are a few pixels to a few hundred pixels large).

#include "render/cpu_raster.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace confluent {
namespace {

constexpr int kSubpixelBits = 8;
constexpr std::int64_t kOne = 1 << kSubpixelBits;
// Vertices farther than this outside the image (pixels) go through the clipping path, which keeps
// the fixed-point products far from overflow.
constexpr double kGuardPx = 16384.0;

struct FixedVertex {
  std::int64_t u = 0, v = 0;  // 1/256 pixel: coverage
  double pixel_u = 0, pixel_v = 0;  // unrounded: the depth plane (rounding would tilt it, badly so near a horizon)
  float inverse_z = 0;
};

// Where Draw writes.
struct RasterTarget {
  int width = 0;
  int row_begin = 0, row_end = 0;
  float* inverse_depth = nullptr;
  std::int32_t* face_ids = nullptr;
  float min_inverse_z = 0;  // 1 / far
};

// floor(x + 0.5), inline (std::lround and std::lrint are library calls here).
std::int64_t RoundToInt(double x) {
  const double t = x + 0.5;
  const std::int64_t i = static_cast<std::int64_t>(t);
  return static_cast<double>(i) > t ? i - 1 : i;
}

std::int64_t CeilDiv(std::int64_t a) { return -((-a) >> kSubpixelBits); }  // ceil(a / 256)
std::int64_t FloorDiv(std::int64_t a) { return a >> kSubpixelBits; }        // floor(a / 256)

// Edge a->b includes pixel centres exactly on it when it is a "top-left" edge of a positively
// oriented triangle (a consistent choice: an edge shared by two triangles runs opposite ways).
bool IncludesTies(const FixedVertex& a, const FixedVertex& b) {
  const std::int64_t du = b.u - a.u, dv = b.v - a.v;
  return dv < 0 || (dv == 0 && du > 0);
}

// Rasterises one triangle; with `cull`, only when it is a front face, else in either orientation.
void RasterTriangle(FixedVertex a, FixedVertex b, FixedVertex c, std::int32_t face, bool cull, const RasterTarget& t,
                    PixelBox* box) {
  // Twice the signed area in image coordinates (x right, y down). A face counter-clockwise seen
  // from outside appears with area < 0 (the y axis points down), as in ClipFromCamera + glFrontFace(GL_CW).
  std::int64_t area = (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
  if (area == 0) return;
  if (area > 0) {
    if (cull) return;  // back face
  } else {
    std::swap(b, c);
    area = -area;
  }
  const std::int64_t min_u = std::min({a.u, b.u, c.u}), max_u = std::max({a.u, b.u, c.u});
  const std::int64_t min_v = std::min({a.v, b.v, c.v}), max_v = std::max({a.v, b.v, c.v});
  const int x0 = static_cast<int>(std::max<std::int64_t>(CeilDiv(min_u), 0));
  const int x1 = static_cast<int>(std::min<std::int64_t>(FloorDiv(max_u), t.width - 1));
  const int y0 = static_cast<int>(std::max<std::int64_t>(CeilDiv(min_v), t.row_begin));
  const int y1 = static_cast<int>(std::min<std::int64_t>(FloorDiv(max_v), t.row_end - 1));
  if (x0 > x1 || y0 > y1) return;
  const float max_iz = std::max({a.inverse_z, b.inverse_z, c.inverse_z});
  if (max_iz < t.min_inverse_z) return;  // beyond the far plane
  const float min_iz = std::min({a.inverse_z, b.inverse_z, c.inverse_z});

  // 1 / z = A u + B v + C, through the unrounded vertices (pixel units).
  const double u0 = a.pixel_u, v0 = a.pixel_v;
  const double du1 = b.pixel_u - u0, dv1 = b.pixel_v - v0, du2 = c.pixel_u - u0, dv2 = c.pixel_v - v0;
  const double d = du1 * dv2 - du2 * dv1;
  if (!(std::abs(d) > 1e-12)) return;
  const double diz1 = static_cast<double>(b.inverse_z) - a.inverse_z, diz2 = static_cast<double>(c.inverse_z) - a.inverse_z;
  const double A = (diz1 * dv2 - diz2 * dv1) / d, B = (diz2 * du1 - diz1 * du2) / d;
  const double C = a.inverse_z - A * u0 - B * v0;

  // Edge functions E_pq(p) = (q.u - p.u) (v - p.v) - (q.v - p.v) (u - p.u), >= 0 inside; ties
  // count for top-left edges only (bias -1 otherwise, on integers).
  const FixedVertex* from[3] = {&b, &c, &a};
  const FixedVertex* to[3] = {&c, &a, &b};
  std::int64_t row_e[3], step_x[3], step_y[3];
  const std::int64_t pu = static_cast<std::int64_t>(x0) * kOne, pv = static_cast<std::int64_t>(y0) * kOne;
  for (int k = 0; k < 3; ++k) {
    const FixedVertex& p = *from[k];
    const FixedVertex& q = *to[k];
    row_e[k] = (q.u - p.u) * (pv - p.v) - (q.v - p.v) * (pu - p.u) - (IncludesTies(p, q) ? 0 : 1);
    step_x[k] = -(q.v - p.v) * kOne;
    step_y[k] = (q.u - p.u) * kOne;
  }
  const float step_iz = static_cast<float>(A);
  bool wrote = false;
  for (int y = y0; y <= y1; ++y) {
    std::int64_t e0 = row_e[0], e1 = row_e[1], e2 = row_e[2];
    float iz = static_cast<float>(A * x0 + B * y + C);
    float* depth_row = t.inverse_depth + static_cast<std::size_t>(y) * t.width;
    std::int32_t* id_row = t.face_ids ? t.face_ids + static_cast<std::size_t>(y) * t.width : nullptr;
    for (int x = x0; x <= x1; ++x) {
      if ((e0 | e1 | e2) >= 0) {
        const float value = std::clamp(iz, min_iz, max_iz);
        if (value > depth_row[x] && value >= t.min_inverse_z) {
          depth_row[x] = value;
          if (id_row) id_row[x] = face;
          wrote = true;
        }
      }
      e0 += step_x[0];
      e1 += step_x[1];
      e2 += step_x[2];
      iz += step_iz;
    }
    row_e[0] += step_y[0];
    row_e[1] += step_y[1];
    row_e[2] += step_y[2];
  }
  if (wrote) {
    if (box->empty()) {
      *box = PixelBox{x0, y0, x1 + 1, y1 + 1};
    } else {
      box->x0 = std::min(box->x0, x0);
      box->y0 = std::min(box->y0, y0);
      box->x1 = std::max(box->x1, x1 + 1);
      box->y1 = std::max(box->y1, y1 + 1);
    }
  }
}

// A point of a clipped polygon, camera frame.
struct ClipPoint {
  double x, y, z;
};

}  // namespace

void CpuRasterOptions::Check() const {
  RequireOption(near_m > 0.0 && std::isfinite(near_m), "CpuRasterOptions.near_m", near_m, "> 0 and finite");
  RequireOptions(far_m > near_m && std::isfinite(far_m), "CpuRasterOptions.near_m", near_m, "CpuRasterOptions.far_m",
                 far_m, "near_m < far_m < infinity");
}

CpuRasterizer::CpuRasterizer(const RowMatrixX3i& faces, int num_vertices, const CpuRasterOptions& options)
    : options_(options) {
  options_.Check();
  std::vector<std::int32_t> compact(static_cast<std::size_t>(std::max(num_vertices, 0)), -1);
  faces_.resize(static_cast<std::size_t>(faces.rows()));
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int v = faces(f, k);
      if (v < 0 || v >= num_vertices)
        throw InputError("mesh", "face " + std::to_string(f) + " refers to vertex " + std::to_string(v) + " of " +
                                     std::to_string(num_vertices));
      if (compact[v] < 0) {
        compact[v] = static_cast<std::int32_t>(used_vertices_.size());
        used_vertices_.push_back(v);
      }
      faces_[f][k] = compact[v];
    }
}

void CpuRasterizer::Project(const Camera& camera, const RowMatrixX3f& vertices_in_world, CpuRasterFrame* frame) const {
  frame->width = camera.width;
  frame->height = camera.height;
  frame->fx = camera.K(0, 0);
  frame->fy = camera.K(1, 1);
  frame->cx = camera.K(0, 2);
  frame->cy = camera.K(1, 2);
  frame->skew = camera.K(0, 1);
  frame->vertices.resize(used_vertices_.size());
  const Eigen::Matrix3d& R = camera.rotation;
  const Eigen::Vector3d& T = camera.translation;
  const double near = options_.near_m;
  const double lo_u = -kGuardPx, hi_u = camera.width + kGuardPx, lo_v = -kGuardPx, hi_v = camera.height + kGuardPx;
  for (std::size_t i = 0; i < used_vertices_.size(); ++i) {
    const auto X = vertices_in_world.row(used_vertices_[i]);
    const double x = R(0, 0) * X(0) + R(0, 1) * X(1) + R(0, 2) * X(2) + T(0);
    const double y = R(1, 0) * X(0) + R(1, 1) * X(1) + R(1, 2) * X(2) + T(1);
    const double z = R(2, 0) * X(0) + R(2, 1) * X(1) + R(2, 2) * X(2) + T(2);
    CpuRasterFrame::Vertex& out = frame->vertices[i];
    out.x = static_cast<float>(x);
    out.y = static_cast<float>(y);
    out.z = static_cast<float>(z);
    out.fast = false;
    if (!(z >= near)) continue;
    const double iz = 1.0 / z;
    const double u = (frame->fx * x + frame->skew * y) * iz + frame->cx, v = frame->fy * y * iz + frame->cy;
    out.inverse_z = static_cast<float>(iz);
    if (!(u > lo_u && u < hi_u && v > lo_v && v < hi_v)) continue;
    out.pixel_u = static_cast<float>(u);
    out.pixel_v = static_cast<float>(v);
    out.u = static_cast<std::int32_t>(RoundToInt(u * kOne));
    out.v = static_cast<std::int32_t>(RoundToInt(v * kOne));
    out.fast = true;
  }
}

PixelBox CpuRasterizer::Draw(const CpuRasterFrame& frame, int row_begin, int row_end, float* inverse_depth,
                             std::int32_t* face_ids) const {
  PixelBox box;
  RasterTarget t;
  t.width = frame.width;
  t.row_begin = std::max(row_begin, 0);
  t.row_end = std::min(row_end, frame.height);
  t.inverse_depth = inverse_depth;
  t.face_ids = face_ids;
  t.min_inverse_z = static_cast<float>(1.0 / options_.far_m);
  if (t.row_end <= t.row_begin || frame.width <= 0) return box;
  const std::int64_t band_lo = static_cast<std::int64_t>(t.row_begin) * kOne;
  const std::int64_t band_hi = static_cast<std::int64_t>(t.row_end - 1) * kOne;
  const bool cull = options_.cull_back_faces;
  // Clipping planes (camera frame, a x + b y + c z + d >= 0): near, then the guard band.
  const double G = kGuardPx, W = frame.width, H = frame.height;
  const double planes[5][4] = {{0, 0, 1, -options_.near_m},
                               {frame.fx, frame.skew, frame.cx + G, 0},
                               {-frame.fx, -frame.skew, W + G - frame.cx, 0},
                               {0, frame.fy, frame.cy + G, 0},
                               {0, -frame.fy, H + G - frame.cy, 0}};
  auto to_fixed = [&](const ClipPoint& p) {
    const double z = std::max(p.z, options_.near_m);
    FixedVertex out;
    out.pixel_u = (frame.fx * p.x + frame.skew * p.y) / z + frame.cx;
    out.pixel_v = frame.fy * p.y / z + frame.cy;
    out.u = RoundToInt(out.pixel_u * kOne);
    out.v = RoundToInt(out.pixel_v * kOne);
    out.inverse_z = static_cast<float>(1.0 / z);
    return out;
  };
  std::vector<ClipPoint> polygon, clipped;
  for (std::size_t f = 0; f < faces_.size(); ++f) {
    const CpuRasterFrame::Vertex& a = frame.vertices[faces_[f][0]];
    const CpuRasterFrame::Vertex& b = frame.vertices[faces_[f][1]];
    const CpuRasterFrame::Vertex& c = frame.vertices[faces_[f][2]];
    const std::int32_t face = static_cast<std::int32_t>(f);
    if (a.fast && b.fast && c.fast) {
      // Rows outside the band: cheap rejection before the setup.
      const std::int64_t min_v = std::min({a.v, b.v, c.v}), max_v = std::max({a.v, b.v, c.v});
      if (max_v < band_lo || min_v > band_hi) continue;
      RasterTriangle(FixedVertex{a.u, a.v, a.pixel_u, a.pixel_v, a.inverse_z},
                     FixedVertex{b.u, b.v, b.pixel_u, b.pixel_v, b.inverse_z},
                     FixedVertex{c.u, c.v, c.pixel_u, c.pixel_v, c.inverse_z}, face, cull, t, &box);
      continue;
    }
    if (a.z < options_.near_m && b.z < options_.near_m && c.z < options_.near_m) continue;
    // Orientation from the camera frame: a face whose outward normal (counter-clockwise) points
    // away from the camera centre is a back face.
    const Eigen::Vector3d pa(a.x, a.y, a.z), pb(b.x, b.y, b.z), pc(c.x, c.y, c.z);
    const double facing = (pb - pa).cross(pc - pa).dot(pa);
    if (cull && !(facing < 0.0)) continue;
    polygon = {{pa.x(), pa.y(), pa.z()}, {pb.x(), pb.y(), pb.z()}, {pc.x(), pc.y(), pc.z()}};
    for (const auto& plane : planes) {  // Sutherland-Hodgman
      clipped.clear();
      for (std::size_t i = 0; i < polygon.size(); ++i) {
        const ClipPoint& p = polygon[i];
        const ClipPoint& q = polygon[(i + 1) % polygon.size()];
        const double dp = plane[0] * p.x + plane[1] * p.y + plane[2] * p.z + plane[3];
        const double dq = plane[0] * q.x + plane[1] * q.y + plane[2] * q.z + plane[3];
        if (dp >= 0) clipped.push_back(p);
        if ((dp >= 0) != (dq >= 0)) {
          const double s = dp / (dp - dq);
          clipped.push_back({p.x + s * (q.x - p.x), p.y + s * (q.y - p.y), p.z + s * (q.z - p.z)});
        }
      }
      polygon.swap(clipped);
      if (polygon.size() < 3) break;
    }
    if (polygon.size() < 3) continue;
    const FixedVertex first = to_fixed(polygon[0]);
    FixedVertex previous = to_fixed(polygon[1]);
    for (std::size_t i = 2; i < polygon.size(); ++i) {
      const FixedVertex next = to_fixed(polygon[i]);
      RasterTriangle(first, previous, next, face, /*cull=*/false, t, &box);
      previous = next;
    }
  }
  return box;
}

PixelBox CpuRasterizer::DrawDepth(const Camera& camera, const RowMatrixX3f& vertices_in_world, CpuRasterFrame* frame,
                                  std::vector<float>* camera_z, const PixelBox* previous) const {
  Project(camera, vertices_in_world, frame);
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
  if (previous != nullptr && camera_z->size() == pixels)
    FillBox(camera_z->data(), camera.width, *previous, 0.0f);
  else
    camera_z->assign(pixels, 0.0f);
  const PixelBox box = Draw(*frame, 0, camera.height, camera_z->data());
  for (int y = box.y0; y < box.y1; ++y) {
    float* row = camera_z->data() + static_cast<std::size_t>(y) * camera.width;
    for (int x = box.x0; x < box.x1; ++x) row[x] = row[x] > 0.0f ? 1.0f / row[x] : 0.0f;
  }
  return box;
}

}  // namespace confluent
