#pragma once
// A scan taken in the performer's first pose whose registered template differs from the first
// tracked one where the tracker erred at frame 0 (a hand turned, a forearm folded the wrong way).
// Neither pose alone serves as the deformation's reference: the registered one moves frame 0 of
// the animated scan off the scan by the tracker's error, the tracked one carries that error into
// every later frame. So the reference is the registered pose, and the first frames ease from it
// into the tracked poses: frame 0 of the animated scan is the scan, later frames follow the tracker.

#include "core/mesh.h"
#include "tracking/body_template.h"

namespace confluent {

struct FirstPoseSeam {
  TemplatePose registered;     // the template registered to the scan (the deformation's reference)
  TemplatePose first_tracked;  // the pose tracked at frame 0
  int frames = 10;             // frames from here on take the tracked poses unchanged
};

// Frames over which the seam eases at `fps`: 0.4 s, at least 2.
int FirstPoseSeamFrames(double fps);

// The share of the correction (registered relative to first_tracked) applied at `frame`: 1 at
// frame 0, falling as a half cosine to 0 at seam.frames and after.
double FirstPoseSeamWeight(const FirstPoseSeam& seam, int frame);

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
