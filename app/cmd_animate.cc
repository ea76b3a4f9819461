// confluent animate: the arguments of Confluent Motion driven by a template mesh sequence or a
// motion-capture file (pipeline/animation.h), and its report on the terminal.

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <string>

#include "app/commands.h"
#include "core/bvh_retarget.h"
#include "core/error.h"
#include "core/mesh_io.h"
#include "pipeline/animation.h"
#include "pipeline/run_folder.h"

namespace confluent::app {
namespace {

void Print(const AnimationLog& log) {
  for (const std::string& line : log.info) std::printf("%s\n", line.c_str());
  for (const std::string& line : log.warnings) std::fprintf(stderr, "warning: %s\n", line.c_str());
  std::fflush(stdout);
}

int RunAnimate(const ParsedArgs& args, const Context& context) {
  const std::string scan_path = args.get("scan");
  const std::string out_dir = args.get("out");
  AnimationOptions options;
  options.format = args.get("format", "ply");
  std::transform(options.format.begin(), options.format.end(), options.format.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (options.format != "ply" && options.format != "obj")
    throw UsageError("--format: expected ply or obj, got '" + options.format + "'");
  const bool bvh = args.has("bvh");
  if (bvh == args.has("template-sequence")) throw UsageError("give exactly one of --template-sequence DIR and --bvh FILE");
  const std::string render = args.get("render");
  if (args.has("render") && render != "orbit") throw UsageError("--render: expected orbit, got '" + render + "'");
  options.render_orbit = render == "orbit";
  options.render_width = args.get_int("render-width", options.render_width);
  options.render_height = args.get_int("render-height", options.render_height);
  if (options.render_width < 16 || options.render_height < 16 || options.render_width > 8192 || options.render_height > 8192)
    throw UsageError("--render-width/--render-height: must be within [16, 8192]");
  const std::string singularities = args.get("singularities", "intermediate");
  if (singularities != "intermediate" && singularities != "slerp" && singularities != "none")
    throw UsageError("--singularities: expected intermediate, slerp or none, got '" + singularities + "'");
  options.motion.intermediate_reference = singularities == "intermediate" && !args.has("no-intermediate-reference");
  options.motion.slerp_paths = singularities == "slerp";
  options.pc2 = args.has("pc2");
  options.write_template = args.has("write-template");
  options.correspondences_source = args.get("correspondences", out_dir + "/correspondences.json");
  const double fps = args.get_double("fps", kAssumedFrameRate);
  if (!(fps > 0.0 && fps <= 1000.0)) throw UsageError("--fps: must be within (0, 1000]");

  const double start = NowSeconds();
  const Mesh scan = ReadMesh(scan_path);
  std::printf("scan %s: %d vertices, %d faces (read in %.2f s)\n", scan_path.c_str(), scan.num_vertices(),
              scan.num_faces(), NowSeconds() - start);
  std::filesystem::create_directories(out_dir);
  AnimationLog log;
  TemplateMotion source;
  if (bvh) {
    BvhMotionSourceOptions source_options;
    source_options.bvh_path = args.get("bvh");
    source_options.correspondences_path = args.get("correspondences");
    source_options.motion.fps = fps;
    source_options.motion.speed = args.get_double("speed", 1.0);
    source_options.motion.max_frames = args.get_int("frames", source_options.motion.max_frames);
    source_options.motion.retarget.joint_map = ParseBvhJointMap(args.get("bvh-map"), "--bvh-map");
    const std::string up = args.get("bvh-up", "auto");
    if (up != "auto" && up != "y" && up != "z") throw UsageError("--bvh-up: expected auto, y or z, got '" + up + "'");
    source_options.motion.retarget.up_axis = up == "auto" ? 'a' : up[0];
    source = BvhMotionOfTemplate(source_options, scan_path, scan, out_dir, &log);
  } else {
    SequenceMotionOptions source_options;
    source_options.dir = args.get("template-sequence");
    source_options.correspondences_path = args.get("correspondences");
    source_options.reference_frame = args.get_int("reference-frame", 0);
    source_options.augment = args.has("augment");
    source_options.fps = fps;
    source = SequenceMotion(source_options, scan_path, scan, out_dir, &log);
  }
  Print(log);
  const AnimationSummary summary =
      AnimateScan(scan, scan_path, source, out_dir, options, context.make_progress ? context.make_progress() : ProgressCallback());
  Print(summary.log);
  return 0;
}

}  // namespace

CommandSpec MakeAnimateCommand() {
  CommandSpec spec;
  spec.name = "animate";
  spec.summary = "animate a scan from a template mesh sequence or a BVH file (Confluent Motion)";
  spec.usage = "--scan S (--correspondences C --template-sequence DIR [--reference-frame N] | --bvh FILE [--correspondences C]) "
               "--out DIR [--render orbit]";
  spec.description =
      "Transfers the motion of an animated template onto the scan S through the triangle correspondences C\n"
      "(correspondences.json), following de Aguiar et al. 2006: harmonic interpolation of the correspondence\n"
      "rotations and a Poisson reconstruction, both factored once. The template motion is either a mesh\n"
      "sequence (--template-sequence: one .obj/.ply per frame in DIR, name order, fixed topology; the scan and\n"
      "the reference frame, default 0, must be roughly aligned) or a motion-capture file (--bvh: the BVH is\n"
      "retargeted to the 16-segment body template registered to the scan, whose registration C holds when it was\n"
      "written by `confluent correspond`; CMU, Mixamo, MakeHuman ... joint names are mapped automatically, --bvh-map\n"
      "overrides; resampled at --fps). Without C, the template is registered to the scan and the pairs are\n"
      "placed automatically (written to DIR/correspondences.json). Writes DIR/<frame:06d>.ply (frames numbered from 0, vertex colours\n"
      "kept), atomically; --pc2 also writes scan.pc2 with rest.ply for Blender's Mesh Cache modifier;\n"
      "--render orbit renders the animated scan with its colours along an orbit into DIR/orbit/<frame>.png and\n"
      "DIR/orbit.mp4.";
  spec.options = {
      {"scan", "S", "the scan (.obj/.ply) in its reference pose", false, true},
      {"correspondences", "C", "correspondences.json (template <-> scan triangles; with --bvh also the registration)"},
      {"template-sequence", "DIR", "folder of template meshes, one per frame"},
      {"reference-frame", "N", "template frame in the scan's reference pose (default 0)"},
      {"bvh", "FILE", "motion-capture file to perform (retargeted to the registered template)"},
      {"bvh-map", "T=B,...", "BVH joint names for template joints, e.g. left_shoulder=LeftArm"},
      {"bvh-up", "AXIS", "up axis of the BVH: auto (default), y or z"},
      {"fps", "F", "output frame rate of a BVH motion, and of the orbit video (default 25)"},
      {"speed", "S", "BVH playback speed factor (default 1)"},
      {"frames", "N", "animate at most N frames of the BVH"},
      {"out", "DIR", "output folder", false, true},
      {"format", "ply|obj", "output mesh format (default ply)"},
      {"augment", "", "add pairs on cylindrical parts (report section 4.2) and write DIR/correspondences.json"},
      {"pc2", "", "also write DIR/scan.pc2 and DIR/rest.ply"},
      {"write-template", "", "also write the posed template meshes to DIR/template/<frame>.ply"},
      {"render", "orbit", "render the animated scan along an orbit (DIR/orbit/<frame>.png, DIR/orbit.mp4)"},
      {"render-width", "PX", "orbit image width (default 640)"},
      {"render-height", "PX", "orbit image height (default 480)"},
      {"singularities", "MODE", "near-180-degree rotations (report 4.3): intermediate (default), slerp or none"},
      {"no-intermediate-reference", "", "same as --singularities none"},
  };
  spec.run = RunAnimate;
  return spec;
}

}  // namespace confluent::app
