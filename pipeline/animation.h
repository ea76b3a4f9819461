#pragma once
// Confluent Motion of a scan driven by a template motion (`confluent animate`): the motion from a
// template mesh sequence or from a motion-capture file (BVH) through the 16-segment body template
// registered to the scan, the deformed frames written as meshes, and optionally an orbit render.

#include <functional>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/progress.h"
#include "deform/confluent_motion.h"
#include "deform/correspondences.h"
#include "pipeline/run_manifest.h"
#include "tracking/template_motion.h"

namespace confluent {

// Lines for the terminal: information, and warnings (each naming its file or frame).
struct AnimationLog {
  std::vector<std::string> info;
  std::vector<std::string> warnings;
};

// The template motion that drives the scan: the reference mesh and a vertex set per frame.
struct TemplateMotion {
  Mesh reference;
  Correspondences correspondences;
  int num_frames = 0;
  double fps = kAssumedFrameRate;
  std::function<RowMatrixX3d(int)> frame_vertices;
  std::string description;
  double front_azimuth_deg = 90.0;  // azimuth (0 = +x, 90 = +y) of the direction the body faces at frame 0
};

struct SequenceMotionOptions {
  std::string dir;                   // one .obj/.ply per frame, in name order, one topology
  std::string correspondences_path;  // template <-> scan pairs (required)
  int reference_frame = 0;           // the frame in the scan's reference pose
  bool augment = false;              // add pairs on cylindrical parts (writes OUT/correspondences.json)
  double fps = kAssumedFrameRate;
};

// A template mesh sequence from files. Throws UsageError, or InputError naming a file.
TemplateMotion SequenceMotion(const SequenceMotionOptions& options, const std::string& scan_path, const Mesh& scan,
                              const std::string& out_dir, AnimationLog* log);

struct BvhMotionSourceOptions {
  std::string bvh_path;
  // correspondences.json with the template's registration (`confluent correspond`); "": register
  // the template to the scan and place the pairs (written to OUT/correspondences.json)
  std::string correspondences_path;
  TemplateBvhMotionOptions motion;   // retargeting, fps, speed, frame limit
};

// The body template registered to the scan, posed by the retargeted BVH.
TemplateMotion BvhMotionOfTemplate(const BvhMotionSourceOptions& options, const std::string& scan_path,
                                   const Mesh& scan, const std::string& out_dir, AnimationLog* log);

struct AnimationOptions {
  std::string format = "ply";        // of OUT/<frame:06d>.<format>: ply or obj
  bool pc2 = false;                  // also OUT/scan.pc2 and OUT/rest.ply (Blender's Mesh Cache)
  bool write_template = false;       // also OUT/template/<frame>.ply
  bool render_orbit = false;         // OUT/orbit/<frame>.png and OUT/orbit.mp4
  int render_width = 640, render_height = 480;
  ConfluentMotionOptions motion;
  std::string correspondences_source;  // the pairs' file, named in errors
};

struct AnimationSummary {
  int frames = 0;
  int singular_frames = 0;  // frames deformed through an intermediate reference
  AnimationLog log;
};

// Deforms `scan` through `source`'s frames into `out_dir`. Throws InputError naming a frame
// with another vertex count, OutputError when a file cannot be written.
AnimationSummary AnimateScan(const Mesh& scan, const std::string& scan_path, const TemplateMotion& source,
                             const std::string& out_dir, const AnimationOptions& options,
                             const ProgressCallback& progress);

}  // namespace confluent
