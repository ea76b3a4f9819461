#pragma once
// Body joints from 2D landmarks that several calibrated cameras place (BlazePose's 33, see
// silhouette/person_segmenter.h): each joint's landmark is triangulated from the cameras that
// agree on it, robust to a camera that misplaces it and to one that swaps the person's left and
// right (a detector looking at the back). The result is evidence beside the silhouettes: where
// silhouettes cannot tell a forearm folded forward from one folded back, the landmarks can.

#include <Eigen/Core>
#include <array>
#include <vector>

#include "calib/camera.h"
#include "core/body_model.h"

namespace confluent {

constexpr int kBodyLandmarks = 33;
// One camera's landmarks, BlazePose order (0 nose ... 11/12 shoulders, 13/14 elbows, 15/16
// wrists, 23/24 hips, 25/26 knees, 27/28 ankles, 31/32 toes; odd = the person's left): image
// pixels x, y and visibility in [0, 1].
using BodyLandmarks = std::array<Eigen::Vector3f, kBodyLandmarks>;

struct LandmarkJointsOptions {
  double min_visibility = 0.5;     // a camera's landmark counts from this visibility
  // A camera agrees with a triangulated point when it projects within this fraction of the
  // image diagonal of its landmark (12.8 px at 512x384).
  double agree_fraction = 0.02;
  int min_cameras = 3;             // cameras that must agree (2 when only 2 see the joint)
  // Throws UsageError naming the bad field.
  void Check() const;
};

// The template joints TriangulateLandmarkJoints places.
constexpr int kTriangulatedJoints = 14;

// Template joints placed by the landmarks.
struct LandmarkJoints {
  std::vector<Eigen::Vector3d> position;  // kNumTemplateJoints, world metres (zero where unknown)
  std::vector<int> cameras;               // per joint: cameras that agree (0 = unknown)
  std::vector<double> rms_px;             // per joint: reprojection rms over those cameras
  // Per hand (0 = the person's left, 1 = right): the midpoint of the index and pinky knuckles
  // (BlazePose 19/17 and 20/18), which points the hand from the wrist (BlazePose places it 4-13
  // degrees off the true hand's direction on the suite's 512x384 frames); cameras that agree on
  // both knuckles (the fewer of the two; 0 = unknown).
  std::array<Eigen::Vector3d, 2> knuckles{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  std::array<int, 2> knuckle_cameras{0, 0};
  bool known(int joint) const { return joint < static_cast<int>(cameras.size()) && cameras[joint] > 0; }
  int num_known() const;
};

// Triangulates the limb joints (shoulders, elbows, wrists, hips, knees, ankles, toes) and the
// hands' knuckles from `views[c]` (one per rig camera; null where a camera has none; world z up).
// Each camera's left and right are settled on the shoulders and hips (a camera may swap them);
// which side is the person's left follows from where the nose and the toes point (what most
// cameras say when neither is placed). A joint is placed where at least `min_cameras` cameras
// agree.
LandmarkJoints TriangulateLandmarkJoints(const Rig& rig, const std::vector<const BodyLandmarks*>& views,
                                         const LandmarkJointsOptions& options = {});

}  // namespace confluent
