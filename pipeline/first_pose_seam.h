#pragma once
// A scan taken in the performer's first pose whose registered template differs from the first
// tracked one where the tracker erred at frame 0 (a hand turned, a forearm folded the wrong way).
// Neither pose alone serves as the deformation's reference: the registered one moves frame 0 of
// the animated scan off the scan by the tracker's error, the tracked one carries that error into
// every later frame. So the reference is the registered pose, and the first frames ease from it
// into the tracked poses: frame 0 of the animated scan is the scan, later frames follow the tracker.

#include <functional>
#include <limits>
#include <optional>

#include "core/mesh.h"
#include "tracking/body_template.h"

namespace confluent {

struct FirstPoseSeam {
  TemplatePose registered;     // the template registered to the scan (the deformation's reference)
  TemplatePose first_tracked;  // the pose tracked at frame 0
  int frames = 10;             // frames from here on take the tracked poses unchanged
  // ... and so do the frames from this one on: the silhouettes showed that the tracker found the
  // scan's pose by itself there (FirstPoseSeamEnd).
  int tracked_from = std::numeric_limits<int>::max();
};

// Frames over which the seam eases at `fps`: 0.4 s, at least 2.
int FirstPoseSeamFrames(double fps);

// The share of the correction (registered relative to first_tracked) applied at `frame`: 1 at
// frame 0, falling as a half cosine to 0 at seam.frames and after; 0 from seam.tracked_from on.
double FirstPoseSeamWeight(const FirstPoseSeam& seam, int frame);

// The first frame in 1 .. seam.frames - 1 whose tracked pose (tracked(frame); null: not tracked)
// explains that frame's silhouettes better than the seam's pose (overlap(frame, pose): e.g. the
// mean IoU with the frame's masks; nullopt: unknown): the tracker has undone its frame-0 error by
// itself (a limb that a later frame's fit found), and correcting that error again would turn the
// limb past the truth. seam.frames when there is none or the search stops at a frame not tracked
// or without an overlap.
int FirstPoseSeamEnd(const BodyTemplate& body, const FirstPoseSeam& seam,
                     const std::function<const TemplatePose*(int)>& tracked,
                     const std::function<std::optional<double>(int, const TemplatePose&)>& overlap);

// `tracked`, the pose tracked at `frame`, corrected by FirstPoseSeamWeight of the seam's
// correction: per ball joint and at the root the rotation from first_tracked to registered
// (scaled along its geodesic), per hinge angle and for the root translation the difference.
// Frame 0's tracked pose gives `registered`.
TemplatePose FirstPoseSeamPose(const BodyTemplate& body, const FirstPoseSeam& seam, const TemplatePose& tracked,
                               int frame);

// Moves `vertices`, the template posed by `tracked` (with `shape`) at `frame`, as FirstPoseSeamPose
// moves its pose (each vertex by the difference of the two posed templates); nothing from
// seam.frames on.
void ApplyFirstPoseSeam(const BodyTemplate& body, const BodyShape& shape, const FirstPoseSeam& seam,
                        const TemplatePose& tracked, int frame, RowMatrixX3d* vertices);

}  // namespace confluent
