#pragma once
// The body template driven by a skeletal motion (a retargeted BVH, report section 5: the biped
// template with one closed mesh per bone): poses of the core skeleton BodyTemplate::MakeSkeleton
// turn into posed template meshes, a sequence with fixed topology that Confluent Motion takes.

#include <string>
#include <vector>

#include "core/bvh_retarget.h"
#include "core/mesh.h"
#include "core/skeleton.h"
#include "tracking/body_template.h"

namespace confluent {

// The template mesh (16 closed segments, face_labels = BodySegment, same vertex order as
// BodyTemplate::PosedMesh) posed by `pose`, a pose of body.MakeSkeleton(shape): each segment
// moves rigidly with its joint.
Mesh PosedTemplateMesh(const BodyTemplate& body, const BodyShape& shape, const Pose& pose);

// Moves a motion of body.MakeSkeleton(shape) rigidly (a turn about the vertical plus a shift)
// so that its first frame stands where `reference` stands: same pelvis position in x and y,
// same heading (the direction (left hip - right hip) x z), and its lowest ankle/toe joint over
// the whole motion at the height of the reference's lowest one. Does nothing to an empty motion.
void PlaceMotionAtReference(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& reference,
                            std::vector<Pose>* motion);

// Options of TemplateMotionFromBvh.
struct TemplateBvhMotionOptions {
  BvhRetargetOptions retarget;  // name map overrides and the BVH's up axis
  double fps = 25.0;            // output frame rate (the BVH is resampled)
  double speed = 1.0;           // playback speed factor
  int max_frames = 1 << 30;     // at most this many frames
  // Throws UsageError for bad values.
  void Check() const;
};

// Reads a BVH file, retargets it to the template with `shape` and resamples it: one pose of
// body.MakeSkeleton(shape) per output frame, placed at `reference` (PlaceMotionAtReference).
// `retarget` (optional) receives the retargeting result without its poses. Throws InputError
// naming the file for a bad or unmappable BVH.
std::vector<Pose> TemplateMotionFromBvh(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& reference,
                                        const std::string& bvh_path, const TemplateBvhMotionOptions& options = {},
                                        BvhRetargetResult* retarget = nullptr);

}  // namespace confluent
