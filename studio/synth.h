#pragma once
// `confluent synth`: renders a synthetic multi-camera capture of an actor in the studio, in the
// recorded camera folder layout (docs/ARCHITECTURE.md section 3), plus a separate ground-truth
// folder.
//
// Capture folder:  intri.yml, extri.yml (every camera, held-out ones included),
//                  images/<cam>/000000.png ..., background/<cam>.png (clean plates), scan.ply.
// Ground truth:    masks/<cam>/000000.png (0/255), meshes/000000.ply (posed actor, same
//                  topology as scan.ply), scan.ply (rest mesh with colours and segment labels),
//                  skeleton.json, skin.json (skeleton and skinning weights, studio/skin_io.h),
//                  joints.json (per-frame joint positions and rotations; skinned actors only:
//                  the procedural one or a rigged mesh), cameras (intri.yml, extri.yml),
//                  synth.json (options).

#include <string>

#include "core/progress.h"
#include "core/skinning.h"
#include "studio/actor.h"
#include "studio/motion.h"
#include "studio/rig.h"
#include "studio/scene.h"

namespace confluent {

// Everything `confluent synth` can change.
struct StudioSynthOptions {
  std::string capture_dir;        // output capture folder (required)
  std::string ground_truth_dir;   // empty: "<capture>_gt" beside the capture folder
  StudioActorOptions actor;
  StudioMotionOptions motion;
  StudioRigOptions rig;
  StudioSceneOptions scene;
  FloorShadowOptions shadow;
  SkinningMethod skinning = SkinningMethod::kDualQuaternion;
  // Instead of the procedural actor: a folder of per-frame meshes (.obj/.ply, read in name
  // order, fixed topology). `sequence_up_axis` is 'z' or 'y' (a Y-up sequence is rotated to Z-up);
  // the sequence is moved so that frame 0 stands centred on the origin with its lowest point on
  // the floor. Meshes without colours get procedural ones.
  std::string actor_sequence_dir;
  // Instead of the procedural actor: a rigged mesh (rest pose, world Z up, metres, facing +y)
  // and its skeleton and skinning weights (studio/skin_io.h), performing the motion.
  std::string actor_mesh_path;
  std::string actor_skin_path;
  char sequence_up_axis = 'z';
  // The scan (scan.ply) is the actor's rest mesh (-1), or the actor as posed at this frame of the
  // performance: a scan taken in the performer's first pose (crouched, arms against the body).
  int scan_frame = -1;
  double noise_sigma = 2.0;       // Gaussian sensor noise, 8-bit grey levels (0 = none)
  double gain_spread = 0.06;      // per-camera gain drawn from [1 - spread, 1 + spread]
  unsigned seed = 1;              // noise and gains
  int threads = 2;                // image post-processing and encoding threads
  // Throws UsageError for bad values (also of the nested options).
  void Check() const;
};

// What SynthesizeCapture produced.
struct StudioSynthSummary {
  std::string capture_dir;
  std::string ground_truth_dir;
  int num_frames = 0;
  int num_cameras = 0;
  int num_vertices = 0;
  int num_triangles = 0;
  double seconds = 0.0;  // wall-clock time
};

// The default ground-truth folder for a capture folder: "<parent>/<name>_gt".
std::string DefaultGroundTruthDir(const std::string& capture_dir);

// Renders and writes the capture and its ground truth. Reports progress per frame ("synth").
// Throws UsageError for bad options, InputError for an unreadable actor sequence (naming the
// file), OutputError when writing fails, RenderContextError when no GL context can be made.
StudioSynthSummary SynthesizeCapture(const StudioSynthOptions& options, const ProgressCallback& progress = {});

}  // namespace confluent
