#pragma once
// The studio's built-in performance: a keyframed motion of the studio skeleton with large,
// varied movement (arms over the head, a full turn, a kick, a crouch), smoothly interpolated.

#include <vector>

#include "core/skeleton.h"

namespace confluent {

// Sampling of the default performance.
struct StudioMotionOptions {
  int num_frames = 100;   // frames to sample
  double fps = 25.0;      // sampling rate; frames past the end hold the final (rest) pose
  double speed = 1.0;     // playback speed factor (2 = twice as fast)
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// Length of the default performance in seconds at speed 1.
double DefaultPerformanceDuration();

// Samples the default performance for `skeleton`, which must have the studio joint names
// (StudioJointNames(); UsageError otherwise). Keyframes hold joint angles that are
// interpolated with a C1 cubic (Catmull-Rom-like Hermite) spline and composed into local
// rotations; the root height is adjusted every frame so that the lower foot stays on the floor.
// Frame f is at time f / fps * speed seconds. Returns num_frames poses.
std::vector<Pose> DefaultPerformance(const Skeleton& skeleton, const StudioMotionOptions& options = {});

}  // namespace confluent
