#pragma once
// The studio's built-in performance: a keyframed motion of the studio skeleton with large,
// varied movement (arms over the head, a full turn, a kick, a crouch), smoothly interpolated.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/bvh_retarget.h"
#include "core/skeleton.h"

namespace confluent {

// Sampling of the default performance.
struct StudioMotionOptions {
  int num_frames = 100;   // frames to sample
  double fps = 25.0;      // sampling rate; frames past the end hold the final (rest) pose
  double speed = 1.0;     // playback speed factor (2 = twice as fast)
  // A BVH file to perform instead of the built-in performance (empty: built-in). It is
  // retargeted to the actor's skeleton (core/bvh_retarget.h); frames past its end are dropped.
  std::string bvh_path;
  BvhRetargetOptions bvh;  // name-map overrides, axes and placement of the BVH motion
  double bvh_start_s = 0.0;  // where in the BVH the performance starts, seconds
  // Perform the BVH on the spot: its slow travel (the pelvis path averaged over 1 s) is removed,
  // keeping the sway and steps about it (KeepPerformanceInVolume).
  bool bvh_in_place = false;
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// Length of the default performance in seconds at speed 1.
double DefaultPerformanceDuration();

// Samples the default performance for `skeleton`, which must have the studio joint names
// (BodyJointNames(); UsageError otherwise). Keyframes hold joint angles that are
// interpolated with a C1 cubic (Catmull-Rom-like Hermite) spline and composed into local
// rotations; the root height is adjusted every frame so that the lower foot stays on the floor.
// Frame f is at time f / fps * speed seconds. Returns num_frames poses.
std::vector<Pose> DefaultPerformance(const Skeleton& skeleton, const StudioMotionOptions& options = {});

// Samples `options.bvh_path` retargeted to `skeleton` (studio joint names): frame f is the BVH
// at time f / fps * speed seconds (poses interpolated); at most num_frames frames, none past the
// BVH's last frame. `retarget` (optional) receives the retargeting result (mapping, units,
// warnings) without its per-BVH-frame poses. Throws InputError naming the BVH file for an
// unreadable or unmappable BVH, UsageError for bad options.
std::vector<Pose> BvhPerformance(const Skeleton& skeleton, const StudioMotionOptions& options,
                                 BvhRetargetResult* retarget = nullptr);

// Where KeepPerformanceInVolume put a performance.
struct PerformancePlacement {
  double travel_m = 0.0;        // the pelvis path's largest distance from its centre, as performed
  bool made_in_place = false;   // the slow travel was removed (StudioMotionOptions::bvh_in_place)
  double radius_m = 0.0;        // the pelvis path's largest distance from the centre afterwards
};

// Moves `poses` (of `skeleton`) horizontally so that the centre of the pelvis path's bounding box
// is at `centre` (x, y). With `in_place` the path averaged over a sliding 1 s window (`fps`) is
// removed first. Throws InputError naming `source` when the pelvis still leaves the circle of
// `volume_radius_m` about the centre, saying how far it travels and what to change.
PerformancePlacement KeepPerformanceInVolume(std::vector<Pose>* poses, const Skeleton& skeleton,
                                             const Eigen::Vector2d& centre, double volume_radius_m, double fps,
                                             bool in_place, const std::string& source);

// The performance `options` choose: BvhPerformance when bvh_path is set, else DefaultPerformance.
std::vector<Pose> StudioPerformance(const Skeleton& skeleton, const StudioMotionOptions& options = {});

}  // namespace confluent
