// confluent synth: render a synthetic multi-camera capture of an actor in the studio, with
// ground truth (studio/synth.h).

#include <cstdio>
#include <string>

#include "app/commands.h"
#include "core/error.h"
#include "core/bvh_retarget.h"
#include "studio/presets.h"

namespace confluent::app {
namespace {

int RunSynth(const ParsedArgs& args, const Context& context) {
  StudioSynthOptions options = StudioSynthPreset(args.get("preset", "default"), "--preset");
  options.capture_dir = args.get("out");
  options.ground_truth_dir = args.get("gt");
  options.motion.num_frames = args.get_int("frames", options.motion.num_frames);
  options.motion.fps = args.get_double("fps", options.motion.fps);
  options.motion.speed = args.get_double("speed", options.motion.speed);
  options.rig.width_px = args.get_int("width", options.rig.width_px);
  options.rig.height_px = args.get_int("height", options.rig.height_px);
  options.rig.num_ring_cameras = args.get_int("cameras", options.rig.num_ring_cameras);
  options.rig.num_heldout_cameras = args.get_int("heldout", options.rig.num_heldout_cameras);
  options.rig.focal_px = args.get_double("focal", options.rig.focal_px);
  options.rig.k1 = args.get_double("k1", options.rig.k1);
  options.rig.ring_radius_m = args.get_double("radius", options.rig.ring_radius_m);
  options.actor.target_triangles = args.get_int("triangles", options.actor.target_triangles);
  options.actor.height_m = args.get_double("actor-height", options.actor.height_m);
  options.actor.torso_girth = args.get_double("girth", options.actor.torso_girth);
  options.actor.arm_girth = args.get_double("girth", options.actor.arm_girth);
  options.actor.leg_girth = args.get_double("girth", options.actor.leg_girth);
  options.scene.green_screen = args.has("green-screen");
  options.noise_sigma = args.get_double("noise", options.noise_sigma);
  options.threads = args.get_int("threads", options.threads);
  const int seed = args.get_int("seed", 1);
  if (seed < 0) throw UsageError("--seed: must be >= 0");
  options.seed = options.actor.seed = options.rig.seed = options.scene.seed = static_cast<unsigned>(seed);
  const std::string skinning = args.get("skinning", "dq");
  if (skinning == "linear") options.skinning = SkinningMethod::kLinear;
  else if (skinning != "dq") throw UsageError("--skinning: expected dq or linear, got '" + skinning + "'");
  options.actor_sequence_dir = args.get("actor-sequence");
  options.actor_mesh_path = args.get("actor-mesh");
  options.actor_skin_path = args.get("actor-skin");
  const std::string up = args.get("up", "z");
  if (up != "y" && up != "z") throw UsageError("--up: expected y or z, got '" + up + "'");
  options.sequence_up_axis = up[0];
  if (!options.actor_sequence_dir.empty() && !args.has("frames")) options.motion.num_frames = 1 << 20;
  options.motion.bvh_path = args.get("bvh");
  options.motion.bvh.joint_map = ParseBvhJointMap(args.get("bvh-map"), "--bvh-map");
  const std::string bvh_up = args.get("bvh-up", "auto");
  if (bvh_up != "auto" && bvh_up != "y" && bvh_up != "z") throw UsageError("--bvh-up: expected auto, y or z, got '" + bvh_up + "'");
  options.motion.bvh.up_axis = bvh_up == "auto" ? 'a' : bvh_up[0];
  options.motion.bvh_start_s = args.get_double("bvh-start", 0.0);
  options.motion.bvh_in_place = args.has("bvh-in-place");
  options.scan_frame = args.get_int("scan-frame", -1);
  if ((args.has("bvh-start") || args.has("bvh-in-place")) && options.motion.bvh_path.empty())
    throw UsageError("--bvh-start and --bvh-in-place go with --bvh FILE");
  if (!options.motion.bvh_path.empty() && !options.actor_sequence_dir.empty())
    throw UsageError("--bvh drives a skinned actor; it cannot be combined with --actor-sequence");
  if (!options.motion.bvh_path.empty() && !args.has("frames")) options.motion.num_frames = 1 << 20;
  const StudioSynthSummary summary = SynthesizeCapture(options, context.make_progress());
  std::printf("wrote %s: %d cameras x %d frames (actor: %d vertices, %d triangles) in %.1f s\n",
              summary.capture_dir.c_str(), summary.num_cameras, summary.num_frames, summary.num_vertices,
              summary.num_triangles, summary.seconds);
  std::printf("ground truth: %s\n", summary.ground_truth_dir.c_str());
  return 0;
}

}  // namespace

CommandSpec MakeSynthCommand() {
  CommandSpec spec;
  spec.name = "synth";
  spec.summary = "render a synthetic studio capture of an actor, with ground truth";
  spec.usage = "--out CAPTURE [options]";
  spec.description =
      "Renders a procedural actor (a watertight, skinned, clothed body, ~120K triangles) performing the\n"
      "built-in motion (arms over the head, a turn, a kick, a crouch; 25 fps) in a studio with a tiled floor,\n"
      "textured walls and a soft shadow, seen by a ring of cameras plus held-out cameras. Writes the recorded\n"
      "camera folder (intri.yml, extri.yml, images/<cam>/<frame>.png, background/<cam>.png, scan.ply) and a\n"
      "ground-truth folder (masks, per-frame meshes, joints.json, skeleton.json, skin.json, scan.ply).\n"
      "World frame: Z up, floor z = 0, metres; the actor faces +y at rest. --preset tiny makes a small test\n"
      "fixture (4+2 cameras, 160x120, 10 frames, ~16K triangles). --actor-sequence DIR renders a mesh\n"
      "sequence (one .obj/.ply per frame, fixed topology) instead of the procedural actor; --actor-mesh M\n"
      "--actor-skin S a rigged body (its skeleton, with the studio's joint names, and skinning weights in S,\n"
      "the format of the ground truth's skin.json). --bvh FILE makes the skinned actor perform a motion-capture file (CMU, Mixamo, MakeHuman ... joint names are mapped\n"
      "automatically, bone directions retargeted, Y-up turned to Z-up), sampled at --fps; without --frames,\n"
      "the whole file.";
  spec.options = {{"out", "CAPTURE", "capture folder to write", false, true},
                  {"gt", "DIR", "ground-truth folder (default: CAPTURE_gt beside CAPTURE)"},
                  {"preset", "NAME", "default or tiny"},
                  {"frames", "N", "number of frames (default 100; a sequence: all its files)"},
                  {"fps", "F", "frame rate of the sampled performance (default 25)"},
                  {"speed", "S", "performance speed factor (default 1)"},
                  {"width", "PX", "image width (default 1024)"},
                  {"height", "PX", "image height (default 768)"},
                  {"cameras", "N", "ring cameras (default 8)"},
                  {"heldout", "N", "held-out cameras (default 2)"},
                  {"focal", "PX", "focal length in pixels (default 1.1 x width)"},
                  {"k1", "K", "radial lens distortion k1 of every camera (default 0)"},
                  {"radius", "M", "ring radius in metres (default 3.8)"},
                  {"triangles", "N", "approximate actor triangle count (default 120000)"},
                  {"actor-height", "M", "actor height in metres (default 1.75)"},
                  {"girth", "F", "girth factor of torso, arms and legs (default 1)"},
                  {"skinning", "NAME", "dq (dual quaternion, default) or linear"},
                  {"green-screen", "", "green floor and walls instead of the textured studio"},
                  {"noise", "SIGMA", "sensor noise in grey levels (default 2)"},
                  {"seed", "N", "random seed (default 1)"},
                  {"threads", "N", "encoding threads (default 2)"},
                  {"actor-sequence", "DIR", "render this mesh sequence instead of the procedural actor"},
                  {"actor-mesh", "MESH", "a rigged actor instead of the procedural one: its rest-pose mesh (with --actor-skin)"},
                  {"actor-skin", "JSON", "the rigged actor's skeleton and skinning weights (skin.json, as in the ground truth)"},
                  {"up", "AXIS", "up axis of the actor sequence: z (default) or y"},
                  {"bvh", "FILE", "perform this BVH motion (retargeted to the actor) instead of the built-in one"},
                  {"bvh-map", "T=B,...", "BVH joint names for actor joints, e.g. left_shoulder=LeftArm"},
                  {"bvh-up", "AXIS", "up axis of the BVH: auto (default), y or z"},
                  {"bvh-start", "S", "start the performance S seconds into the BVH (default 0)"},
                  {"bvh-in-place", "", "perform a travelling BVH on the spot (its slow travel removed)"},
                  {"scan-frame", "N", "the scan is the actor as posed at frame N (default: its rest mesh)"}};
  spec.run = RunSynth;
  return spec;
}

}  // namespace confluent::app
