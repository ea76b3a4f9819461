#pragma once
// Multi-view consistency of one frame's masks: each camera's mask against the visual hull of the
// other cameras (carved through the calibration and projected into it). Gives a confidence per
// camera, and corrects a mask where the others agree: ghosts outside their hull are removed,
// holes inside it are filled.

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "calib/camera.h"
#include "calib/rig_check.h"
#include "core/image.h"
#include "silhouette/background_model.h"

namespace confluent {

// Settings of CheckMultiView.
struct MultiViewOptions {
  // Voxels along the longest side of the box around the hull.
  int grid_resolution = 128;
  // Other cameras that may reject a voxel of a camera's hull (a hole in one camera does not
  // carve the others' hull); -1 = automatic: 1 with 4 or more other cameras, else 0.
  int tolerated_rejections = -1;
  // Ghosts: mask pixels farther than this from the others' hull are removed. Pixels per 1000
  // pixels of image width (scaled with the image).
  double ghost_margin = 8.0;
  // Holes: pixels at least this deep inside the others' hull, and within the closing radius of
  // the mask, are filled (per 1000 pixels of width, as above).
  double hole_margin = 6.0;
  double hole_close = 40.0;
  // Highlights claimed for plate masks (ClaimHighlightsInsideHull): pixels at least this deep
  // inside the others' hull (per 1000 pixels of width).
  double claim_margin = 3.0;
  // A camera-frame whose confidence is below this is flagged.
  double min_confidence = 0.8;
  // The largest hull (of every camera's mask) one person may carve, cubic metres: a person is
  // about 0.07, their hull from 4 cameras a few times that. Masks that hold the same background
  // (a platform, a wall) in several cameras agree with each other and carve a hull far larger;
  // every camera's confidence is then scaled by this over the hull's volume. 0 = no limit.
  double max_hull_volume_m3 = 1.0;
  int threads = 1;  // the visual hulls are carved on this many threads (the same result)
  // Throws UsageError naming the bad field.
  void Check() const;
};

// One camera's mask against the others' hull.
struct ViewConsistency {
  double explained = 0;   // fraction of the mask near the others' hull (1 = no ghosts)
  double covered = 0;     // fraction of the others' strict hull covered by the mask (a hull is larger than the silhouette)
  double confidence = 0;  // min(explained, covered / the frame's median covered), in [0, 1]; 0 for an empty mask
  int added = 0;          // pixels filled by the correction
  int removed = 0;        // pixels removed by the correction
  double hull_volume_m3 = 0;  // of the frame's hull of every camera's mask (the same for every camera)
};

// Checks each camera's mask of one frame (`masks[i]`: 1-channel 0/255 of rig camera i, or empty
// for a camera without a mask: it neither constrains nor is checked) against the hull of the
// others, and corrects the masks of the cameras with `correct[i]` (empty: none). Needs 3 or more
// cameras with masks; with fewer every confidence is 1 and nothing changes. `hulls`, if given,
// receives each camera's projected tolerant hull of the others (empty for cameras without a
// mask), `strict_hulls` the strict one, `underside` the underside of the tolerant hulls. A hull
// larger than options.max_hull_volume_m3 lowers every camera's confidence.
// Throws InputError naming the camera whose mask differs in size from its calibration.
std::vector<ViewConsistency> CheckMultiView(const Rig& rig, std::vector<Image>* masks, const std::vector<bool>& correct,
                                            const MultiViewOptions& options, std::vector<Image>* hulls = nullptr,
                                            std::vector<Image>* strict_hulls = nullptr,
                                            HullUnderside* underside = nullptr);

// The masks after a refinement of some of them (the graph cut) checked against each other
// again: what camera c's refinement added (in `masks[c]`, not in `before[c]`) beyond the hull
// of the others' refined masks is removed (a poster in the shirt's colours beside the body,
// which one camera's cut took); what the mask held before stays, and no hole is filled. A part
// the first hull lacked but most cameras' refinements put back (a shirt of the wall's colour)
// is in the new hull and stays. `masks` and `before` as CheckMultiView's masks (empty for
// cameras kept out); only cameras with `refined[c]` change. Returns the pixels removed per camera.
std::vector<int> RemoveRefinementsTheOthersDoNotShare(const Rig& rig, const std::vector<Image>& before,
                                                      const std::vector<bool>& refined, const MultiViewOptions& options,
                                                      std::vector<Image>* masks);

// What lies below a hull down to the floor (z = 0), seen by `camera` (1-channel 0/255): each
// column of `underside` drawn as a segment from its lowest voxel to the floor, a voxel wide. A
// standing person's feet lie there even when every camera's mask loses them against their
// shadow.
Image ProjectColumnsToFloor(const Camera& camera, const HullUnderside& underside);

// What lies above the top of a hull, seen by `camera` (1-channel 0/255): the columns whose
// highest voxel is within `near_top_m` of the hull's highest, continued `height_m` upwards. A
// performer who hardly moves has a head that every camera's mask may lose (it stays in the
// learned background), so that the hull ends at the shoulders.
Image ProjectColumnsAboveTop(const Camera& camera, const HullUnderside& hull, double near_top_m, double height_m);

// Each camera's projected hull of the others, loose: a voxel stays unless more than half of the
// other cameras with a mask reject it (at most 4), so that a hole several cameras share (skin
// over a floor of its colour, seen against the same tiles) does not carve it. Masks as
// CheckMultiView's (empty: no mask); the hull of a camera without a mask is empty, and every hull
// is empty with fewer than 3 masks. Throws InputError naming a camera whose mask differs in size
// from its calibration.
std::vector<Image> LooseHullsOfTheOthers(const Rig& rig, const std::vector<Image>& masks, const MultiViewOptions& options);

// Claims for `mask` (1-channel 0/255, made with `model` from a clean plate) the pixels of
// `frame` (8-bit RGB) that the model calls a highlight of the background where `hull` (the
// other cameras' projected hull, closed and eroded by options.claim_margin) says the actor is:
// skin over a beige floor is a "highlight" of the floor. Shadows are left alone: the actor's own
// shadow lies on the floor beside the feet, which a coarse hull covers. Returns the number of
// pixels added. Throws UsageError when the sizes differ.
int ClaimHighlightsInsideHull(Image* mask, const Image& frame, const BackgroundModel& model, const Image& hull,
                              const MultiViewOptions& options);

// How far a set of masks can be trusted, from a sample of frames.
// One checked camera-frame.
struct CameraFrameConfidence {
  int camera = 0;  // rig index
  int frame = 0;
  double confidence = 1;
  double hull_volume_m3 = 0;  // of the frame's hull of every camera (0: not known)
};

struct MaskTrust {
  int camera_frames = 0;                 // checked
  std::vector<CameraFrameConfidence> checked;  // each checked camera-frame, in the order given
  int low_confidence = 0;                // of them below options.min_confidence
  double mean_confidence = 1;
  std::vector<double> camera_confidence;  // mean per camera (rig order; 1 for cameras not checked)
  int oversized_hull_frames = 0;  // frames whose hull is larger than one person's
  double largest_hull_m3 = 0;     // the largest hull of the checked frames
  // "" when the masks look fine, else one line with the numbers and what to do.
  std::string warning;
};

// Summarises the confidences of checked camera-frames: the counts, the means, and the warning
// (set when more than a tenth of the camera-frames, or any camera on average, falls below
// `min_confidence`); the warning says so when frames carve hulls larger than
// `max_hull_volume_m3` (0: no limit).
MaskTrust SummarizeMaskTrust(const Rig& rig, const std::vector<CameraFrameConfidence>& confidences,
                             double min_confidence, double max_hull_volume_m3 = 0);

// Reads the masks of `frames` through `read_mask(camera, frame)` (an empty image: no mask for
// that camera) and summarises CheckMultiView's confidence without correcting anything
// (SummarizeMaskTrust with options.min_confidence and options.max_hull_volume_m3).
MaskTrust AssessMaskTrust(const Rig& rig, const std::vector<int>& frames,
                          const std::function<Image(int camera, int frame)>& read_mask, const MultiViewOptions& options);

}  // namespace confluent
