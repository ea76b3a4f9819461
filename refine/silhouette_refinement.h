#pragma once
// Silhouette refinement of an animated scan: after Confluent Motion has posed the scan, its
// outline in each input camera is pulled onto that camera's silhouette (in the spirit of de
// Aguiar et al. 2008, "Performance capture from sparse multi-view video"). The scan's rim
// vertices (surface points on its own outline) are moved perpendicular to their viewing rays
// to the nearest mask edge along the outline's normal; the displacements are spread over the
// surface by a normalised diffusion whose sparse factor is computed once per scan. Pose and
// transfer errors of a few pixels shrink, the shape between the rims stays the scan's.

#include <memory>
#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"

namespace confluent {

// Options of SilhouetteRefiner.
struct SilhouetteRefinementOptions {
  int iterations = 18;         // rim search and diffusion rounds per frame
  // A rim vertex looks for the mask edge this far in and out. Wider reaches cloth that a pose
  // swings out, but snaps to wrong edges more often: 20 px gives +0.08 dB held-out PSNR on the
  // studio default and -0.3 dB on samba.
  double search_px = 12.0;
  double max_rim_cosine = 0.3;  // |normal . viewing ray| below this: a candidate rim vertex
  // Diffusion stiffness relative to the mean diagonal of the cotangent Laplacian: a rim
  // displacement spreads over about 1 / sqrt(spread_stiffness) edges (0.003: ~18 edges). Wider
  // spreading bends the surface between the rims less (studio default, 12 rounds: 0.01 gives a
  // held-out PSNR of 25.86 dB, 0.003 with step_gain 2 gives 26.13).
  double spread_stiffness = 0.003;
  // Far from any rim the displacement fades out: the diffused rim weight is compared with this
  // (larger: more local corrections, smaller: whole limbs follow).
  double fade_weight = 0.05;
  // Each round moves the vertices by this times the spread rim steps (the normalised diffusion
  // under-steps at isolated rims). A round after which the mean IoU over the cameras drops is
  // taken back and made at half the gain, which stays halved (a backtracking line search).
  double step_gain = 2.0;
  int threads = 2;             // cameras examined in parallel
  void Check() const;          // throws UsageError naming an invalid field and its value
};

// What one Refine() call did.
struct SilhouetteRefinementSummary {
  int rim_vertices = 0;         // vertices moved by some camera in the last round
  double mean_shift_m = 0.0;    // mean vertex displacement over all rounds
  double max_shift_m = 0.0;
  // Per camera given to Refine: IoU of the scan's silhouette with the mask before and after
  // (NaN for a camera whose mask is empty, which is skipped).
  std::vector<double> iou_before, iou_after;
};

// Refines frames of one scan (fixed topology). Construction factors the diffusion system.
class SilhouetteRefiner {
 public:
  // `scan` gives the topology and the reference geometry of the Laplacian. Throws
  // InputError("scan", ...) when the system cannot be factored (e.g. an empty mesh).
  explicit SilhouetteRefiner(const Mesh& scan, const SilhouetteRefinementOptions& options = {});
  ~SilhouetteRefiner();
  SilhouetteRefiner(SilhouetteRefiner&&) noexcept;
  SilhouetteRefiner& operator=(SilhouetteRefiner&&) noexcept;

  // The scan's `vertices` (posed, metres) moved towards the silhouettes: masks[i] is the
  // 0/255 silhouette in cameras[i], at the camera's resolution (else std::invalid_argument).
  // Never returns non-finite values. `iterations` >= 0 overrides the options' rounds for this call
  // (e.g. a few rounds to restore the outline after another refinement moved the surface).
  RowMatrixX3d Refine(const RowMatrixX3d& vertices, const std::vector<Camera>& cameras,
                      const std::vector<Image>& masks, SilhouetteRefinementSummary* summary = nullptr,
                      int iterations = -1) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace confluent
