#pragma once
// Retargeting BVH motion capture onto the body's skeleton (core/body_model.h BodyJointNames:
// pelvis, spine, chest, neck, head, head_end,
// {left,right}_{shoulder,elbow,wrist,hand_end,hip,knee,ankle,toe}).
//
// Method. BVH joints are matched to target joints by name (CMU, 3ds-Max CMU, Mixamo, MakeHuman,
// Poser/DAZ and Biped-style names; the spine and chest are picked by height along the BVH's
// pelvis-to-neck chain), with per-joint overrides. Each target bone is then turned so that it
// points where its mapped BVH bone points in every frame, and its twist about the bone follows
// the mapped BVH joint's rotation: with A the rest-pose alignment of the target bone to the BVH
// bone, the target joint's world rotation is R_fix * G_bvh * A, where R_fix (identity when the
// mapped BVH joint drives the bone directly) corrects the swing left by skipped BVH joints.
// The root translation is scaled by the leg-length ratio (target / BVH). The BVH's up axis
// (usually Y) is detected and turned to the world's Z; its length unit is detected from the
// skeleton's height. Axes, height and the alignment A come from the BVH's rest pose, or from its
// first standing frame when the rest pose is not a standing body (all bones along one axis).

#include <Eigen/Core>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/bvh_io.h"
#include "core/skeleton.h"

namespace confluent {

// Options of RetargetBvh.
struct BvhRetargetOptions {
  // Target joint name -> BVH joint name, overriding the automatic mapping ("" unmaps a joint).
  std::map<std::string, std::string> joint_map;
  // The BVH's up axis: 'a' (auto: from the feet towards the head at rest), 'y' or 'z'.
  char up_axis = 'a';
  // Turn the motion about the vertical so that frame 0 faces the target's rest facing (the
  // direction (left hip - right hip) x up); false keeps the BVH's own heading.
  bool face_target = true;
  // Move the motion horizontally so that frame 0's pelvis is above the target's rest pelvis.
  bool center_on_target = true;
  // Shift the motion vertically (one constant for the whole sequence) so that the lowest
  // ankle/toe joint over all frames is as high as the lowest one of the target at rest.
  bool feet_on_floor = true;
  // An arm whose elbow bends about an axis this far (radians) or further from the target's hinge
  // is turned about its bones to bend about the hinge (BvhRetargetResult::elbow_turns_deg);
  // infinity keeps every arm as the rest poses align it.
  double min_hinge_turn_rad = 5.0 * M_PI / 180.0;
  // Throws UsageError for a bad up_axis or min_hinge_turn_rad.
  void Check() const;
};

// A retargeted motion.
struct BvhRetargetResult {
  std::vector<Pose> poses;     // one pose of the target skeleton per BVH frame
  double fps = 0.0;            // BVH frame rate (1 / Frame Time)
  // Target joint name -> the BVH joint it follows (mapped joints only).
  std::map<std::string, std::string> joint_map;
  std::vector<std::string> unmapped;  // target joints without a BVH joint (they follow their parent)
  // The BVH frame whose pose defined the up axis, height and bone alignment because the rest
  // pose is not a standing body; -1: the rest pose did.
  int reference_frame = -1;
  char up_axis = 'y';                 // the BVH up axis used
  std::string unit = "m";             // detected length unit: m, cm, mm, inch or cmu (CMU's 1/0.45 inch)
  double metres_per_unit = 1.0;       // of the detected unit
  double bvh_height = 0.0;            // rest height of the BVH skeleton in its own units
  double translation_scale = 1.0;     // target leg length / BVH leg length (metres per BVH unit)
  // world_from_bvh: turns BVH directions (after the scale) into the target world: up axis to
  // +z and the heading change of face_target.
  Eigen::Matrix3d world_from_bvh = Eigen::Matrix3d::Identity();
  // Per arm ("left", "right"), the turn about its bones that put the BVH's elbow hinge on the
  // target's, degrees (arms left as aligned at rest are absent).
  std::map<std::string, double> elbow_turns_deg;
  std::vector<std::string> warnings;
};

// The automatic name mapping: target joint name -> BVH joint name for each target joint that
// is found in `bvh` (by the name tables; the spine and chest by height, see the file comment, in
// `joint_positions` of the BVH's joints, or at rest when it is empty).
std::map<std::string, std::string> GuessBvhJointMap(const Skeleton& bvh, const std::vector<std::string>& target_names,
                                                    const std::vector<Eigen::Vector3d>& joint_positions = {});

// Retargets `motion` (read with ReadBvh and default options: no scaling, no axis change) to
// `target` (metres, Z up). Throws InputError naming `source` (the BVH path) when an essential
// joint (pelvis, head or neck, and both sides' shoulder, elbow, wrist, hip, knee, ankle) cannot
// be mapped, when an override names a joint the BVH lacks, or when the motion has no frames;
// UsageError for bad options or a target without the studio joint names.
BvhRetargetResult RetargetBvh(const BvhMotion& motion, const Skeleton& target, const BvhRetargetOptions& options = {},
                              const std::string& source = "bvh");

// Reads `path` (ReadBvh; its InputErrors name the file and line) and retargets it.
BvhRetargetResult RetargetBvhFile(const std::string& path, const Skeleton& target,
                                  const BvhRetargetOptions& options = {});

// Samples a pose sequence recorded at `source_fps` at time `time_s` (linear root translation,
// slerped rotations; clamped to the ends). `poses` must not be empty.
Pose SamplePoses(const std::vector<Pose>& poses, double source_fps, double time_s);

// Samples a retargeted motion for playback: frame f at time start_s + f / fps * speed seconds
// of the BVH, at most `max_frames` frames and none past the BVH's last frame. Throws UsageError
// for a non-positive fps or speed, or a start outside [0, the motion's duration].
std::vector<Pose> SampleRetargetedMotion(const BvhRetargetResult& motion, double fps, double speed = 1.0,
                                         int max_frames = 1 << 30, double start_s = 0.0);

// Parses "target=bvh,target=bvh" (e.g. "left_shoulder=LeftArm") into a joint map. Throws
// UsageError naming `flag` for a malformed item.
std::map<std::string, std::string> ParseBvhJointMap(const std::string& text, const std::string& flag = "--bvh-map");

}  // namespace confluent
