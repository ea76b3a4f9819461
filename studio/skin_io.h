#pragma once
// A rigged actor for the studio: a rest-pose mesh plus a skeleton and skinning weights in
// `skin.json`, so `confluent synth` can perform any body that comes with a rig, not only the
// procedural one. The ground truth of every synth with a skinned actor includes its skin.json.
//
// skin.json:
//   {"frame": "...",                                  (free text)
//    "joints": [{"name": "pelvis", "parent": -1, "rest_position": [x, y, z]}, ...],
//    "weights": [[joint, weight, joint, weight, ...], ...]}
// Joints are in topological order (parents first, joint 0 the only root), rest positions in the
// mesh's frame (world Z up, metres, facing +y like the procedural actor). "weights" has one row
// per mesh vertex with up to 4 (joint index, weight) pairs summing to 1. The skeleton must contain
// every joint of BodyJointNames() (core/body_model.h) (extra joints are allowed and follow their parents), so the
// built-in performance and BVH retargeting can drive it.

#include <string>

#include "studio/actor.h"

namespace confluent {

// The skeleton and weights of `actor` as skin.json text.
std::string StudioSkinJson(const StudioActor& actor);

// Reads a rigged actor: the mesh (.obj/.ply; vertex colours kept) and its skin.json. Meshes
// without colours get a neutral grey. Throws InputError naming the file and the problem: an
// unreadable file, bad JSON, a missing studio joint, a parent after its child, a weight row count
// that differs from the mesh's vertex count, a joint index out of range, weights that are negative
// or do not sum to 1, non-finite coordinates.
StudioActor ReadRiggedActor(const std::string& mesh_path, const std::string& skin_path);

}  // namespace confluent
