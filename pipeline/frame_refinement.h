#pragma once
// The refinement of the deform stage, one frame after the other: the deformed scan pulled onto the
// used cameras' silhouettes, then moved until neighbouring cameras agree on the texture, then its
// outline restored by a few silhouette rounds.
//
// The correction a frame needed is much like the one the next frame needs (the scan's shape
// against the template's, a limb the tracker placed a little off). Each frame between keyframes
// therefore starts from the deformation plus the previous frame's correction, carried in each
// vertex's local frame (normal, and tangent towards a neighbour: it turns with the surface), and
// takes fewer rounds. Keyframes (frame % keyframe_interval == 0) start from the
// deformation as it is, so any frame's result depends only on the frames since its keyframe: a
// run resumed or sharded in the middle replays those frames and writes the same scan.
// It pays where the tracking is steady (the demo: +0.3 dB held-out PSNR in half the time) and
// costs where it jitters (samba: -0.5 dB), so `run` keeps every frame a keyframe unless asked.

#include <vector>

#include "calib/camera.h"
#include "core/image.h"
#include "core/mesh.h"
#include "refine/photo_refinement.h"
#include "refine/silhouette_refinement.h"

namespace confluent {

struct FrameRefinementOptions {
  bool photo = true;             // the photo-consistency refinement and the outline rounds after it
  int silhouette_rounds = 18;    // at a keyframe
  int photo_rounds = 5;          // at a keyframe
  int photo_full_resolution_rounds = 2;  // PhotoRefinementOptions::full_resolution_rounds
  int outline_rounds = 6;        // silhouette rounds after the photo refinement
  int keyframe_interval = 1;     // 1: every frame starts from its deformation
  int carried_silhouette_rounds = 6;  // the rounds of a frame that starts from the carried correction
  int carried_photo_rounds = 2;
  int threads = 2;
  void Check() const;  // throws UsageError naming an invalid field and its value
};

// What the refinement of one frame did.
struct FrameRefinementSummary {
  bool carried = false;                 // started from the previous frame's correction
  std::vector<double> iou_start;        // per camera, the IoU the refinement started from (NaN: empty mask)
  std::vector<double> iou_after;        // per camera, after the last round
  PhotoRefinementSummary photo;         // rounds == 0 without the photo refinement
  double silhouette_seconds = 0.0, photo_seconds = 0.0;  // the photo part includes the outline rounds
};

class FrameRefinement {
 public:
  // Factors the diffusion systems of `scan` (the topology of every frame).
  FrameRefinement(const Mesh& scan, const std::vector<Camera>& cameras, const FrameRefinementOptions& options);

  bool IsKeyframe(int frame) const { return frame % options_.keyframe_interval == 0; }

  // The refined vertices of `frame`, deformed as `deformed`: masks[i] (0/255) and images[i]
  // (8-bit, only read with the photo refinement) are cameras[i]'s at this frame. A frame that is
  // not a keyframe starts from the carried correction when the previous call refined frame - 1,
  // else from its deformation.
  RowMatrixX3d Refine(int frame, const RowMatrixX3d& deformed, const std::vector<Image>& masks,
                      const std::vector<Image>& images, FrameRefinementSummary* summary = nullptr);

 private:
  FrameRefinementOptions options_;
  RowMatrixX3i faces_;
  std::vector<int> neighbours_;  // per vertex, the neighbour its local frame points to
  std::vector<Camera> cameras_;
  SilhouetteRefiner silhouette_;
  PhotoRefiner photo_;
  int carried_frame_ = -2;       // the frame whose correction is carried
  RowMatrixX3d carried_;         // its correction per vertex in the vertex's local frame
};

}  // namespace confluent
