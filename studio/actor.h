#pragma once
// The synthetic studio's actor: a procedurally generated, dense, watertight human body built
// around a skeleton with the 16-segment template topology, with procedural clothing colours
// and skinning weights.
//
// Frame and units: world Z up, floor z = 0, metres. At rest the actor stands at the origin in
// a natural A-pose (arms about 40 degrees from the body), facing +y; its right side is +x and
// its left side is -x. Front and back differ: a face (eyes, nose, mouth) and a chest logo at the
// front; hair and back pockets at the back. A wristwatch marks the left wrist.

#include <array>
#include <string>
#include <vector>

#include "core/body_model.h"
#include "core/body_segments.h"
#include "core/mesh.h"
#include "core/skeleton.h"
#include "core/skinning.h"

namespace confluent {


// Proportions and meshing detail of the studio actor.
struct StudioActorOptions {
  double height_m = 1.75;  // standing height (top of the head), metres
  // Girth factors (1 = default build) per body part; they scale the radii, not the lengths.
  double torso_girth = 1.0;
  double arm_girth = 1.0;
  double leg_girth = 1.0;
  double head_size = 1.0;
  double arm_angle_deg = 40.0;  // rest A-pose: angle between the upper arms and the vertical
  // Approximate triangle count of the mesh; the meshing grid cell size is chosen from it
  // (the result is within about 15%). 120K by default; ~12K for test fixtures.
  int target_triangles = 120000;
  int smoothing_iterations = 12;  // Taubin (lambda|mu) smoothing passes after meshing
  unsigned seed = 1;              // seed of the procedural colour noise
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// The actor: its skeleton, rest-pose mesh and skinning weights.
struct StudioActor {
  Skeleton skeleton;  // the body's joints (core/body_model.h), rest pose = the A-pose
  // Rest-pose mesh: watertight, one component, with vertex colours (linear RGB) and
  // face_labels = BodySegment per face.
  Mesh mesh;
  SkinWeights weights;  // one row per mesh vertex, joints of `skeleton`
  // For each BodySegment, the joint whose rotation moves it rigidly.
  std::array<int, kNumBodySegments> segment_joint{};
};

// For each BodySegment, the index (into BodyJointNames(), core/body_model.h) of the joint that
// moves it rigidly.
std::array<int, kNumBodySegments> StudioSegmentJoints();

// The studio skeleton scaled to `options.height_m`, at rest in the A-pose (joint 0 = pelvis).
Skeleton MakeStudioSkeleton(const StudioActorOptions& options = {});

// Builds the actor: an implicit surface (smooth union of tapered elliptic capsules around the
// bones) meshed by marching tetrahedra on a regular grid, Taubin-smoothed, coloured and
// skinned. Deterministic for given options. Throws UsageError for bad options.
StudioActor BuildStudioActor(const StudioActorOptions& options = {});

}  // namespace confluent
