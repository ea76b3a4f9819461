#pragma once
// Projective texturing of a mesh from calibrated input camera images, rendered into novel
// views (free-viewpoint video, held-out evaluation).
//
// Per output pixel, every input camera i that sees the surface point X contributes its image
// colour with a weight (Buehler et al. 2001, "Unstructured Lumigraph Rendering"):
//   - visibility: X's camera z is at most the farthest of the 4 nearest depth-map texels plus
//     depth_bias_m (a shadow-map test; the depth maps are rendered once per frame, lens
//     distortion included, optionally at reduced resolution: visibility_scale, and from a
//     simplified proxy of a large mesh: visibility_faces, the tolerance then grows by the proxy's
//     deviation);
//   - penalty p_i = angle between the novel ray and camera i's ray at X (radians, as the chord
//     sqrt(2 - 2 cos), within 5% below 60 degrees), plus
//     optionally resolution_weight * max(0, |X - C_i| - |X - C_novel|) / |X - C_novel|;
//   - best k: with t = the (k+1)-th smallest penalty (pi when k or fewer cameras see X),
//     w_i = (1 - p_i / t) / p_i for the k best, 0 for the others;
//   - feathering: w_i *= smoothstep(0, feather_px, distance to the nearest edge of the mesh's
//     outline, a depth discontinuity or the mask's outline in camera i), and 0 outside the
//     camera's mask, so seams fade out before the outline;
//   - grazing angles: w_i *= smoothstep(0, grazing_cos, n . direction to camera i).
// Weights are normalised. Where no camera sees X the mesh's own vertex colours are used (or
// fallback_color). A camera that sees nothing contributes nothing; the output never contains
// NaN.
//
// Optional colour balancing: per camera RGB gains fitted by least squares on surface points that
// several cameras see well (log-colour differences; a weak prior keeps the mean gain near 1).

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "render/renderer.h"

namespace confluent {

// Options of ProjectiveTexturer.
struct ProjectiveTextureOptions {
  int best_k = 3;              // cameras blended per pixel, 1..8 (1 = nearest camera only)
  double depth_bias_m = 0.01;  // visibility tolerance: visible when z <= depth map + bias, metres
  // Feathering width near silhouette edges and depth discontinuities, in input-camera pixels
  // (0 = off).
  double feather_px = 8.0;
  // Jump in camera depth between neighbouring pixels (metres) that counts as an occlusion edge
  // for feathering.
  double depth_edge_m = 0.05;
  // Feather also near the edges of the input masks (when masks are given), not only the mesh's
  // own rendered outline.
  bool feather_mask_edges = true;
  double resolution_weight = 0.0;  // weight of the ULR resolution penalty (0 = angle only)
  // Cosine between the surface normal and the direction to the camera below which the
  // camera's weight is ramped down to 0 at grazing angles (0 = off).
  double grazing_cos = 0.2;
  // Skip faces seen from behind, in the depth maps and the novel view: about halves the
  // triangle cost on a software rasteriser. Right for closed meshes oriented counter-clockwise
  // seen from outside (core/mesh.h), such as scans and the body template; turn off for open or
  // inconsistently oriented meshes.
  bool cull_back_faces = true;
  // Resolution of the input cameras' depth and feather maps relative to their images (0..1]:
  // 0.5 renders them at half width and height (feather_px stays in image pixels). Makes SetFrame
  // about a third cheaper, at a cost in quality (studio default, ground-truth geometry: -0.3 dB
  // held-out PSNR at 0.5, -0.1 dB at 0.75).
  double visibility_scale = 1.0;
  // Faces of the proxy the depth maps are drawn from: a mesh with more than 1.5 times as many
  // is simplified once, at construction (vertex clustering that keeps vertices of the mesh, so
  // the proxy follows the animated vertices), and the visibility tolerance grows by the proxy's
  // deviation from the mesh. The depth maps' cost is mostly per triangle on a software
  // rasteriser (a 263K-face mesh: SetFrame about 2 times faster). Studio default scan (118K faces,
  // a 24K-face proxy), ground-truth geometry: held-out PSNR unchanged (31.74 dB). 0 = always draw
  // the full mesh.
  int visibility_faces = 20000;
  // Where the depth maps (cameras without lens distortion) and the novel views' G-buffer are
  // rasterised. kAuto: on the CPU (render/cpu_raster.h, both cores) when the GL context is a
  // software one (llvmpipe: its per-triangle setup is single-threaded and dearer than the CPU
  // rasteriser, and reading its buffers back costs as much again), with GL on a GPU. The images
  // agree to float rounding (same coverage rule and depth interpolation).
  enum class Raster { kAuto, kCpu, kGl };
  Raster raster = Raster::kAuto;
  bool colour_balance = false;  // fit and apply per-camera RGB gains
  int colour_balance_samples = 20000;  // surface points (vertices) sampled for the gain fit
  // Colour of surface no camera sees when the mesh has no vertex colours, RGB in [0,1].
  Eigen::Vector3d fallback_color = Eigen::Vector3d(0.5, 0.5, 0.5);
  // Colour of pixels the mesh does not cover, RGB in [0,1].
  Eigen::Vector3d background = Eigen::Vector3d::Zero();
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// What SetFrame found, per input camera (in the order given to SetFrame).
struct TextureFrameInfo {
  std::vector<int> visible_pixels;           // pixels of each camera's depth map the mesh covers
  std::vector<Eigen::Vector3d> colour_gains; // per camera RGB gain applied (1,1,1 without balancing)
};

// Textures one mesh from a set of input cameras, frame by frame. Per frame, SetFrame renders the
// input cameras' depth maps, feather maps and (optionally) colour gains once and keeps a copy of
// the images; Render then draws any number of novel views (the mesh into a G-buffer, then the
// blending once per covered pixel, on the CPU threads). Rasterisation runs on the CPU or with GL
// (ProjectiveTextureOptions::raster; the CPU on a software GL). Owns GL state (its own EGL context
// plus a MeshRenderer for input cameras with lens distortion); not thread-safe.
class ProjectiveTexturer {
 public:
  // `mesh` gives the topology (faces), the fallback vertex colours (if any) and the initial
  // vertices. Throws InputError("mesh") for a malformed mesh, UsageError for bad options and
  // RenderContextError when no GL context can be created.
  explicit ProjectiveTexturer(const Mesh& mesh, const ProjectiveTextureOptions& options = {},
                              const MeshRendererOptions& renderer = {});
  ~ProjectiveTexturer();
  ProjectiveTexturer(const ProjectiveTexturer&) = delete;
  ProjectiveTexturer& operator=(const ProjectiveTexturer&) = delete;

  // Sets the frame: the mesh's current vertices (same count as the mesh, world frame, metres),
  // the input cameras, their RGB8 images (any 8-bit 1/3/4-channel image is converted; size must
  // match the camera) and optional masks (empty vector = none; else one per camera, 1 channel,
  // nonzero = actor; an empty Image = no mask for that camera). Excluded cameras are simply not
  // passed. Throws InputError for a wrong vertex count, NaN vertices, size mismatches or a bad
  // camera, UsageError for mismatched list lengths.
  void SetFrame(const RowMatrixX3d& vertices, const std::vector<Camera>& cameras, const std::vector<Image>& images,
                const std::vector<Image>& masks = {});

  // Renders the textured mesh into `view` at its resolution (lens distortion applied):
  // colour RGB8 and, when asked, the silhouette (uint8 0/255). Throws InputError when the view
  // fails Camera::Check, UsageError when SetFrame was not called.
  RenderResult Render(const Camera& view, bool want_silhouette = false);

  // RGB factors per input camera (SetFrame's order), applied on top of the colour balance in the
  // following Render calls: for example gains to a real camera's colour response
  // (calib/plate_colour.h) when rendering its view. Kept across SetFrame calls with as many
  // cameras; an empty vector removes them. Throws UsageError before SetFrame or for a wrong count,
  // InputError for a gain that is not finite and positive.
  void SetViewGains(const std::vector<Eigen::Vector3d>& gains);

  // Blended colours of world-space surface points as seen by a viewer straight along each
  // point's normal (for baking textures, export/atlas_bake.h): the same visibility, ULR weights,
  // feathering, grazing ramp and colour gains (balance and SetViewGains) as Render, with the novel
  // view's centre at points.row(i) + view_distance_m * normals.row(i). `points` and `normals` are
  // n x 3, world frame, metres; normals unit length, pointing out of the surface. Writes n x 3
  // RGB8 into `rgb`, and into `seen` 1 where a camera sees the point, 0 where none does (its
  // colour is then 0; the caller picks the fallback, e.g. the mesh's vertex colours). Runs on all
  // cores. Throws UsageError before SetFrame, for mismatched sizes or view_distance_m <= 0.
  void BlendSurfacePoints(const RowMatrixX3f& points, const RowMatrixX3f& normals, double view_distance_m,
                          std::vector<std::uint8_t>* rgb, std::vector<std::uint8_t>* seen) const;

  // Per-camera statistics of the last SetFrame.
  const TextureFrameInfo& frame_info() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace confluent
