#pragma once
// Photo-consistency refinement of an animated scan, after the silhouette refinement: between the
// rims, where silhouettes say nothing, neighbouring input cameras must still agree on the texture.
// Each camera's image is compared with a neighbour's image reprojected into it through the scan.
// Where the surface is off along its normal, the two disagree by a shift along the epipolar
// line; the optical flow between them (DIS, Kroeger et al. 2016) is triangulated with the two
// cameras' rays into a point on the true surface. The per-vertex offsets along the normal are
// spread over the surface by normalised diffusion and the scan moved along its normals, over a
// few rounds. Sub-millimetre offsets matter: a textured view from between two cameras blurs or
// doubles the texture where the surface is off by a fraction of a pixel's footprint.

#include <memory>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"

namespace confluent {

// Options of PhotoRefiner.
struct PhotoRefinementOptions {
  int rounds = 5;               // flow, triangulation and move rounds per frame
  // Cameras compared with each camera: the nearest in direction from the scan. Two cameras that
  // are each other's neighbours are compared once per round, in one camera's image in even
  // rounds and in the other's in odd rounds.
  int neighbours = 2;
  // Each round moves the vertices along their normals by this times the spread offsets (the
  // normalised diffusion under-steps; above 2 the rounds oscillate).
  double step_gain = 1.5;
  // Diffusion stiffness relative to the mean diagonal of the cotangent Laplacian: an offset
  // spreads over about 1 / sqrt(spread_stiffness) edges.
  double spread_stiffness = 0.01;
  double fade_weight = 0.05;    // far from any measured vertex the offset fades out
  // A pixel is used when the surface faces both cameras: |normal . ray| at least this.
  double min_view_cosine = 0.3;
  double max_flow_px = 3.0;       // larger flows are mismatches
  double max_ray_gap_m = 0.004;   // the two rays miss each other by more: flow off the epipolar line
  double max_offset_m = 0.01;     // larger triangulated offsets are outliers
  double visibility_tolerance_m = 0.01;  // a point farther than this behind the neighbour's depth map is hidden
  // The flow's finest pyramid level: 1 stops at half resolution (then upsampled). 0, full
  // resolution, cost 3.5x the time for +0.27 dB held-out PSNR on the studio default (DIS's
  // medium preset, used until 2026-11; now the fast one).
  int flow_finest_scale = 1;
  // The last rounds measure the flow at full resolution instead (finest scale 0): the coarse
  // rounds bring the surface near, the fine ones place it to a fraction of a full-size pixel.
  // 2 of the default 5: +0.25 to +0.54 dB held-out PSNR on four performances at the studio's size,
  // for 1.26x the photo refinement's time per frame (2026-12-06, bench/SUITE.md, bench_photo_studio).
  int full_resolution_rounds = 2;
  // The full-resolution rounds' offsets are less noisy than the half-resolution ones, so they are
  // spread more locally (a fold beside the arm, a crease at the waist), over about
  // 1 / sqrt(full_resolution_spread_stiffness) edges.
  double full_resolution_spread_stiffness = 0.03;
  // DIS's patch stride at full resolution (the fast preset's 4, as at half resolution). 6 places
  // 2.25x fewer patches: the photo refinement 1.07x the time of five half-resolution rounds
  // instead of 1.26x, for 0.04-0.05 dB less held-out PSNR (2026-12-06).
  int full_resolution_patch_stride = 4;
  // Iterations of DIS's variational refinement of the flow, in the last round only: the earlier
  // rounds' moves are measured again by the next round (the fast preset's 5 in every round: 27%
  // more photo-refinement time for +0.01 dB held-out PSNR on the studio default, 2026-11-26).
  int flow_variational_iterations = 5;
  // The same when the last round is at full resolution: there 5 iterations took 1.27x the photo
  // refinement's time for -0.03 to +0.03 dB held-out PSNR (2026-12-06).
  int full_resolution_variational_iterations = 0;
  int outline_margin_px = 3;    // pixels this close to the scan's outline in a camera are not used
  int threads = 2;              // camera pairs processed in parallel
  void Check() const;           // throws UsageError naming an invalid field and its value
};

// What one Refine() call did.
struct PhotoRefinementSummary {
  int rounds = 0;
  long long samples = 0;          // triangulated pixels, summed over the rounds
  int measured_vertices = 0;      // vertices with an offset in the last round
  // Mean flow between each camera's image and its neighbours' reprojections, in pixels, over the
  // used pixels: in the first round (before any move) and in the last one (before its move).
  double first_flow_px = 0.0;
  double last_flow_px = 0.0;
  double mean_shift_m = 0.0;      // mean vertex displacement
};

// Refines frames of one scan (fixed topology). Construction factors the diffusion system.
class PhotoRefiner {
 public:
  // `scan` gives the topology and the reference geometry of the Laplacian. Throws
  // InputError("scan", ...) when the system cannot be factored (e.g. an empty mesh).
  explicit PhotoRefiner(const Mesh& scan, const PhotoRefinementOptions& options = {});
  ~PhotoRefiner();
  PhotoRefiner(PhotoRefiner&&) noexcept;
  PhotoRefiner& operator=(PhotoRefiner&&) noexcept;

  // The scan's `vertices` (posed, metres) moved along their normals until neighbouring cameras
  // agree: images[i] is camera i's frame (8-bit RGB or grey, the camera's size, else
  // std::invalid_argument). Lens distortion is undone internally. Fewer than two cameras: the
  // vertices are returned unchanged. Never returns non-finite values. `rounds` >= 0 overrides the
  // options' rounds for this call.
  RowMatrixX3d Refine(const RowMatrixX3d& vertices, const std::vector<Camera>& cameras,
                      const std::vector<Image>& images, PhotoRefinementSummary* summary = nullptr,
                      int rounds = -1) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace confluent
