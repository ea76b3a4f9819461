// ProjectiveTexturer's per-frame work (SetFrame): every input camera's depth map from the proxy
// mesh, on the CPU rasteriser or with GL (MeshRenderer for cameras with lens distortion), its
// feather map and a copy of its image, per camera on all cores; then the colour balance.

#include <epoxy/gl.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <future>
#include <opencv2/imgproc.hpp>
#include <thread>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "calib/capture.h"
#include "core/cv_interop.h"
#include "core/error.h"
#include "render/projective_texture_impl.h"

namespace confluent {
namespace {

// The camera with its image resized by `scale` (at least 1 pixel).
Camera Scaled(const Camera& camera, double scale) {
  if (scale == 1.0) return camera;
  return ResizedCamera(camera, std::max(1, static_cast<int>(std::lround(camera.width * scale))),
                       std::max(1, static_cast<int>(std::lround(camera.height * scale))));
}

// `mask` at width x height (itself when the size matches or it is empty; else an area-averaged
// copy in `storage`, thresholded at half coverage).
const Image& ScaledMask(const Image& mask, int width, int height, Image* storage) {
  if (mask.empty() || (mask.width == width && mask.height == height)) return mask;
  cv::Mat resized;
  cv::resize(AsCvMat(mask), resized, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  cv::threshold(resized, resized, 127, 255, cv::THRESH_BINARY);
  *storage = ImageFromCvMat(resized);
  return *storage;
}

// Window depth (GL depth buffer in [0, 1] of ClipFromCamera's projection) -> camera z, in place;
// the cleared value 1 (nothing drawn) -> 0.
void WindowDepthToCameraZ(double near_m, double far_m, std::vector<float>* depth) {
  const double a = (far_m + near_m) / (far_m - near_m), b = -2.0 * far_m * near_m / (far_m - near_m);
  for (float& d : *depth) d = d >= 1.0f ? 0.0f : static_cast<float>(b / ((2.0 * d - 1.0) - a));
}

// Asks for transparent huge pages on a large buffer not yet touched (Linux; a hint, ignored
// elsewhere): the blending reads the depth maps and images of 8 cameras (~70 MB) at scattered
// places, and with 4 KB pages it waits on TLB misses.
void AdviseHugePages(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr std::uintptr_t kHuge = 2u << 20;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(data) + kHuge - 1) & ~(kHuge - 1);
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(kHuge - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

// Empties `buffer` and reserves `count` elements in a fresh allocation advised for huge pages.
template <typename T>
void ReserveWithHugePages(std::size_t count, std::vector<T>* buffer) {
  std::vector<T>().swap(*buffer);
  buffer->reserve(count);
  AdviseHugePages(buffer->data(), count * sizeof(T));
}
}  // namespace

// Draws the window depth of the mesh (current vertex buffer) in undistorted camera `i` into its
// depth target; ReadDepth reads it back.
void ProjectiveTexturer::Impl::DrawDepth(int i, const Camera& camera) {
  const int w = camera.width, h = camera.height;
  if (static_cast<int>(depth_targets.size()) <= i) depth_targets.resize(i + 1);
  DepthTarget& target = depth_targets[i];
  if (target.framebuffer == 0) {
    glGenFramebuffers(1, &target.framebuffer);
    glGenRenderbuffers(1, &target.depth);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, target.framebuffer);
  if (target.width != w || target.height != h) {
    glBindRenderbuffer(GL_RENDERBUFFER, target.depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, target.depth);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw RenderContextError("OpenGL: projective texture depth framebuffer " + std::to_string(w) + "x" +
                               std::to_string(h) + " is incomplete");
    target.width = w;
    target.height = h;
  }
  glViewport(0, 0, w, h);
  const GLfloat far_depth = 1.0f;
  glClearBufferfv(GL_DEPTH, 0, &far_depth);
  render_internal::SetMeshRasterState(options.cull_back_faces, GL_LESS);
  const Eigen::Matrix4f clip_from_world =
      (ClipFromCamera(camera.K, w, h, renderer_options.near_m, renderer_options.far_m) * CamFromWorld(camera))
          .cast<float>();
  glUseProgram(depth_program);
  glUniformMatrix4fv(glGetUniformLocation(depth_program, "clip_from_world"), 1, GL_FALSE, clip_from_world.data());
  glBindVertexArray(depth_vertex_array);
  glDrawElements(GL_TRIANGLES, num_depth_faces * 3, GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
  glDisable(GL_CULL_FACE);
  CheckGl("depth map of camera " + camera.name);
}

// Window depth drawn by DrawDepth(i, camera) into `out` (w x h, top row first; 1 where not
// covered). WindowDepthToCameraZ converts it.
void ProjectiveTexturer::Impl::ReadDepth(int i, const Camera& camera, std::vector<float>* out) {
  out->resize(static_cast<std::size_t>(camera.width) * camera.height);
  glBindFramebuffer(GL_FRAMEBUFFER, depth_targets[i].framebuffer);
  glReadPixels(0, 0, camera.width, camera.height, GL_DEPTH_COMPONENT, GL_FLOAT, out->data());
  CheckGl("reading the depth map of camera " + camera.name);
}

void ProjectiveTexturer::Impl::SetFrame(const RowMatrixX3d& vertices, const std::vector<Camera>& input_cameras,
                                        const std::vector<Image>& images, const std::vector<Image>& masks) {
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
  CheckVertices(vertices, "mesh");
  context.MakeCurrent();
  UploadPositions(vertices);

  // Per camera: the depth map (GL or the CPU rasteriser), the feather map and the copy of the
  // image the blending reads.
  camera_z.resize(std::max<std::size_t>(camera_z.size(), n));
  depth_feather.resize(std::max<std::size_t>(depth_feather.size(), n));
  feather_written.resize(std::max<std::size_t>(feather_written.size(), n));
  z_written.resize(std::max<std::size_t>(z_written.size(), n));
  vis_cameras.clear();
  for (const Camera& camera : input_cameras) vis_cameras.push_back(Scaled(camera, options.visibility_scale));
  const double feather_px = options.feather_px * options.visibility_scale;
  static const Image kNoMask;
  scaled_masks.resize(n);
  frame_images.resize(n);
  std::vector<int> visible(n, 0);
  // How camera_z[i] was filled: 0 = to be drawn by the CPU rasteriser, 1 = GL window depth,
  // 2 = camera z (distorted cameras, MeshRenderer).
  std::vector<int> source(n, 0);
  auto process = [&](int i, CpuRasterFrame* raster_frame, FeatherScratch* scratch) {
    const Camera& camera = vis_cameras[i];
    const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
    PixelBox z_box{0, 0, camera.width, camera.height};
    if (source[i] == 0) {
      // CPU: clears only what the last frame drew.
      z_box = depth_rasterizer->DrawDepth(camera, positions, raster_frame, &camera_z[i], &z_written[i]);
    } else if (source[i] == 1) {
      WindowDepthToCameraZ(renderer_options.near_m, renderer_options.far_m, &camera_z[i]);
    }
    z_written[i] = z_box;
    if (depth_feather[i].size() != 2 * pixels) {
      ReserveWithHugePages(2 * pixels, &depth_feather[i]);
      depth_feather[i].assign(2 * pixels, 0.0f);
      feather_written[i] = PixelBox();
    }
    const Image& mask = masks.empty() ? kNoMask : masks[i];
    const Image& map_mask = ScaledMask(mask, camera.width, camera.height, &scaled_masks[i]);
    visible[i] = DepthFeatherMap(camera_z[i].data(), camera.width, camera.height, z_box, map_mask, options,
                                 feather_px, depth_feather[i].data(), &feather_written[i], scratch);
    // The blending reads the images on the CPU: keep them (the caller's may go away).
    if (frame_images[i].data.capacity() < rgb[i]->data.size())
      ReserveWithHugePages(rgb[i]->data.size(), &frame_images[i].data);
    if (rgb[i] == &converted[i]) frame_images[i] = std::move(converted[i]);
    else frame_images[i] = *rgb[i];
  };
  // Cameras with lens distortion: MeshRenderer (exact distortion), on this thread (GL).
  bool distortion_vertices_set = false;
  auto render_distorted = [&](int i) {
    if (!distortion_renderer) {
      distortion_renderer = std::make_unique<MeshRenderer>(renderer_options);
      mesh_handle = distortion_renderer->AddMesh(mesh_topology, "mesh");
    }
    if (!distortion_vertices_set) distortion_renderer->UpdateVertices(mesh_handle, vertices);
    distortion_vertices_set = true;
    RenderRequest request;
    request.color = false;
    request.depth = true;
    request.cull_back_faces = options.cull_back_faces;
    const Image depth = distortion_renderer->Render(vis_cameras[i], request).depth;
    camera_z[i].assign(depth.ptr<float>(), depth.ptr<float>() + depth.data.size() / sizeof(float));
    source[i] = 2;
    context.MakeCurrent();
  };
  // Declared before the jobs: the workers use it until the jobs are joined below.
  std::atomic<int> next{0};
  std::vector<std::future<void>> jobs;
  try {
    if (cpu_raster) {
      // Distorted cameras first (GL, this thread), then every camera's maps on all workers.
      for (int i = 0; i < n; ++i)
        if (vis_cameras[i].has_distortion()) render_distorted(i);
      const int workers = std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, std::min(n, 8));
      raster_frames.resize(std::max<std::size_t>(raster_frames.size(), std::max(workers, 1)));
      feather_scratch.resize(std::max<std::size_t>(feather_scratch.size(), std::max(workers, 1)));
      auto work = [&](int worker) {
        for (int i = next++; i < n; i = next++) process(i, &raster_frames[worker], &feather_scratch[worker]);
      };
      for (int worker = 1; worker < workers; ++worker) jobs.push_back(std::async(std::launch::async, work, worker));
      work(0);
    } else {
      // GL: all undistorted depth maps are drawn before the first read-back (llvmpipe bins one
      // camera while it rasterises the previous); each camera's feather map is computed on a
      // worker thread while the next map is read.
      for (int i = 0; i < n; ++i)
        if (!vis_cameras[i].has_distortion()) DrawDepth(i, vis_cameras[i]);
      feather_scratch.resize(std::max<std::size_t>(feather_scratch.size(), n));
      for (int i = 0; i < n; ++i) {
        if (vis_cameras[i].has_distortion()) {
          render_distorted(i);
        } else {
          ReadDepth(i, vis_cameras[i], &camera_z[i]);
          source[i] = 1;
        }
        jobs.push_back(std::async(std::launch::async, process, i, nullptr, &feather_scratch[i]));
      }
    }
    for (std::future<void>& job : jobs) job.get();
  } catch (...) {
    for (std::future<void>& job : jobs)
      if (job.valid()) job.wait();
    throw;
  }
  std::vector<CameraFrame> frames(n);
  info = TextureFrameInfo();
  for (int i = 0; i < n; ++i) {
    frames[i].camera = input_cameras[i];
    frames[i].map_camera = vis_cameras[i];
    frames[i].depth_feather = depth_feather[i].data();
    frames[i].image = &frame_images[i];
    frames[i].visible_pixels = visible[i];
    info.visible_pixels.push_back(visible[i]);
  }
  gains = options.colour_balance ? FitGains(vertices, frames) : std::vector<Eigen::Vector3d>(n, Eigen::Vector3d::Ones());
  info.colour_gains = gains;
  cameras = input_cameras;
  if (view_gains.size() != cameras.size()) view_gains.clear();
  SetBlendCameras();
  frame_set = true;
}

}  // namespace confluent
