// ProjectiveTexturer::Render: the novel view's covered rectangle and undistortion map, the mesh
// rasterised on the CPU (face ids and 1 / z) or into a GL G-buffer, the per-pixel blending on all
// cores, and the composite over the background.

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "core/cv_interop.h"
#include "core/error.h"
#include "render/projective_texture_impl.h"

namespace confluent {

void ProjectiveTexturer::Impl::EnsureFramebuffer(int width, int height) {
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

// The bounding box of the mesh's projected vertices (current frame) in a pinhole camera, plus a
// pixel; the whole buffer when a vertex is not in front of the near plane.
ProjectiveTexturer::Impl::PixelRect ProjectiveTexturer::Impl::CoveredRect(const Eigen::Matrix4d& cam_from_world,
                                                                          const Eigen::Matrix3d& K, int width,
                                                                          int height) const {
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
const ProjectiveTexturer::Impl::ViewMap& ProjectiveTexturer::Impl::MapFor(const Camera& view) {
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

RenderResult ProjectiveTexturer::Impl::Render(const Camera& view, bool want_silhouette) {
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
BlendInput ProjectiveTexturer::Impl::MakeBlendInput(const Camera& view) const {
  BlendInput in;
  in.view_center = view.center_in_world().cast<float>();
  in.depth_bias = static_cast<float>(options.depth_bias_m + proxy_bias_m);
  in.resolution_weight = static_cast<float>(options.resolution_weight);
  in.grazing_cos = static_cast<float>(options.grazing_cos);
  in.best_k = options.best_k;
  return in;
}

// Render on the CPU into `readback` (ideal pinhole buffer `ideal`, RGBA8): the mesh rasterised
// into face ids and 1 / z (two row halves on two threads), then per covered pixel the world point
// from the pixel's ray, the face normal and the blending; the mesh's colour where no camera sees.
void ProjectiveTexturer::Impl::RenderCpu(const Camera& ideal, const PixelRect& rect) {
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
void ProjectiveTexturer::Impl::RenderGl(const Camera& view, const Eigen::Matrix3d& K, int width, int height,
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
RenderResult ProjectiveTexturer::Impl::Composite(const Camera& view, int width, int height, const ViewMap* map,
                                                 bool want_silhouette) {
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
void ProjectiveTexturer::Impl::SetBlendCameras() {
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

void ProjectiveTexturer::BlendSurfacePoints(const RowMatrixX3f& points, const RowMatrixX3f& normals,
                                            double view_distance_m, std::vector<std::uint8_t>* rgb,
                                            std::vector<std::uint8_t>* seen) const {
  const Impl& s = *impl_;
  if (!s.frame_set) throw UsageError("ProjectiveTexturer::BlendSurfacePoints: SetFrame was not called");
  if (points.rows() != normals.rows())
    throw UsageError("ProjectiveTexturer::BlendSurfacePoints: " + std::to_string(points.rows()) + " points and " +
                     std::to_string(normals.rows()) + " normals");
  if (!(view_distance_m > 0.0))
    throw UsageError("ProjectiveTexturer::BlendSurfacePoints: view_distance_m must be > 0, got " +
                     std::to_string(view_distance_m));
  const std::size_t n = static_cast<std::size_t>(points.rows());
  rgb->assign(3 * n, 0);
  seen->assign(n, 0);
  const BlendInput in = s.MakeBlendInput(Camera());
  const auto distance = static_cast<float>(view_distance_m);
  constexpr int kChunk = 4096;
  const int chunks = static_cast<int>((n + kChunk - 1) / kChunk);
  Impl::ForRowBands(chunks, [&](int chunk) {
    BlendInput point_in = in;
    const std::size_t end = std::min(n, static_cast<std::size_t>(chunk + 1) * kChunk);
    for (std::size_t i = static_cast<std::size_t>(chunk) * kChunk; i < end; ++i) {
      const Eigen::Vector3f X = points.row(static_cast<Eigen::Index>(i)).transpose();
      const Eigen::Vector3f normal = normals.row(static_cast<Eigen::Index>(i)).transpose();
      point_in.view_center = X + distance * normal;
      (*seen)[i] = BlendPixel(point_in, s.blend_cameras, X, normal, rgb->data() + 3 * i) ? 1 : 0;
    }
  });
}

}  // namespace confluent
