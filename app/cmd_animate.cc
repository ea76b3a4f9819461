// confluent animate: Confluent Motion, a scan animated by a template mesh sequence or by a
// motion-capture file (BVH) through the 16-segment body template (deform/confluent_motion.h,
// tracking/template_motion.h), optionally rendered along an orbit into PNGs and an MP4.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "app/commands.h"
#include "core/bvh_retarget.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/video_writer.h"
#include "deform/confluent_motion.h"
#include "deform/correspondences.h"
#include "deform/point_cache.h"
#include "render/camera_path.h"
#include "render/renderer.h"
#include "tracking/body_template.h"
#include "pipeline/scan_correspondence.h"
#include "tracking/scan_registration.h"
#include "tracking/template_motion.h"

namespace confluent::app {
namespace {

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string Lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// The .obj/.ply files of `dir`, in name order.
std::vector<std::string> SequenceFiles(const std::string& dir) {
  std::error_code error;
  if (!std::filesystem::is_directory(dir, error)) throw InputError(dir, "not a folder");
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    const std::string extension = Lower(entry.path().extension().string());
    if (entry.is_regular_file() && (extension == ".obj" || extension == ".ply")) files.push_back(entry.path().string());
  }
  if (error) throw InputError(dir, "cannot list the folder: " + error.message());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw InputError(dir, "no .obj or .ply meshes in the template sequence folder");
  return files;
}

std::string FrameName(int frame, const std::string& extension) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d.%s", frame, extension.c_str());
  return name;
}

// The template motion that drives the scan: the reference mesh and a vertex set per frame.
struct TemplateMotion {
  Mesh reference;
  Correspondences correspondences;
  int num_frames = 0;
  double fps = 25.0;
  std::function<RowMatrixX3d(int)> frame_vertices;
  std::string description;
  double front_azimuth_deg = 90.0;  // azimuth (0 = +x, 90 = +y) of the direction the body faces at frame 0
};

// --template-sequence DIR: meshes from files.
TemplateMotion SequenceMotion(const ParsedArgs& args, const std::string& scan_path, const Mesh& scan,
                              const std::string& out_dir) {
  const std::string sequence_dir = args.get("template-sequence");
  const std::string correspondences_path = args.get("correspondences");
  if (correspondences_path.empty()) throw UsageError("--template-sequence needs --correspondences C");
  const std::vector<std::string> frames = SequenceFiles(sequence_dir);
  const int reference_frame = args.get_int("reference-frame", 0);
  if (reference_frame < 0 || reference_frame >= static_cast<int>(frames.size()))
    throw UsageError("--reference-frame: must be in [0, " + std::to_string(frames.size() - 1) + "], got " +
                     std::to_string(reference_frame));
  TemplateMotion motion;
  motion.reference = ReadMesh(frames[reference_frame]);
  motion.correspondences = ReadCorrespondences(correspondences_path);
  ValidateCorrespondences(motion.correspondences, motion.reference.num_faces(), scan.num_faces(), correspondences_path);
  if (args.has("augment")) {
    const std::size_t given = motion.correspondences.pairs.size();
    motion.correspondences = AugmentCorrespondences(motion.reference, scan, motion.correspondences);
    motion.correspondences.scan_path = std::filesystem::absolute(scan_path).string();
    WriteCorrespondences(out_dir + "/correspondences.json", motion.correspondences);
    std::fprintf(stderr, "augmented %zu given pairs to %zu (written to %s/correspondences.json)\n", given,
                 motion.correspondences.pairs.size(), out_dir.c_str());
  }
  motion.num_frames = static_cast<int>(frames.size());
  motion.fps = args.get_double("fps", 25.0);
  const Mesh reference = motion.reference;
  motion.frame_vertices = [frames, reference_frame, reference](int i) {
    if (i == reference_frame) return reference.vertices;
    const Mesh frame = ReadMesh(frames[i]);
    if (frame.num_vertices() != reference.num_vertices() || frame.num_faces() != reference.num_faces() ||
        frame.faces != reference.faces)
      throw InputError(frames[i], "topology differs from the reference frame " + frames[reference_frame] + " (" +
                                      std::to_string(frame.num_vertices()) + " vs " +
                                      std::to_string(reference.num_vertices()) + " vertices, " +
                                      std::to_string(frame.num_faces()) + " vs " +
                                      std::to_string(reference.num_faces()) + " faces)");
    return frame.vertices;
  };
  motion.description = std::to_string(frames.size()) + " frames of " + sequence_dir;
  return motion;
}

// --bvh FILE: the body template registered to the scan (from --correspondences C or computed),
// posed by the retargeted BVH.
TemplateMotion BvhMotionOfTemplate(const ParsedArgs& args, const std::string& scan_path, const Mesh& scan,
                                   const std::string& out_dir) {
  const std::string bvh_path = args.get("bvh");
  const std::string correspondences_path = args.get("correspondences");
  auto body = std::make_shared<BodyTemplate>();
  ScanRegistration registration;
  TemplateMotion motion;
  double start = Now();
  if (correspondences_path.empty()) {
    // Automatic: register the template to the scan, place the pairs, keep both for re-runs.
    const ScanCorrespondence result = CorrespondTemplateToScan(*body, scan, scan_path, ScanCorrespondenceOptions());
    registration = result.registration;
    motion.reference = result.reference;
    motion.correspondences = result.correspondences;
    std::printf("template registered to the scan: rms residual %.4g (scan units, %.3g m per unit), %zu correspondences "
                "placed automatically (%.2f s)\n",
                registration.rms_residual_m, registration.metres_per_unit, motion.correspondences.pairs.size(),
                Now() - start);
    for (const std::string& warning : registration.warnings)
      std::fprintf(stderr, "warning: %s: %s\n", scan_path.c_str(), warning.c_str());
    const std::string written = out_dir + "/correspondences.json";
    WriteScanCorrespondence(result, *body, scan_path, out_dir + "/template_reference.ply", "template_reference.ply",
                            written);
    std::printf("written to %s\n", written.c_str());
  } else {
    registration = ReadTemplateRegistration(correspondences_path, *body);
    motion.correspondences = ReadCorrespondences(correspondences_path);
    motion.reference = body->PosedMesh(registration.shape, registration.pose);
    std::printf("template registration from %s: %zu pairs (%.2f s)\n", correspondences_path.c_str(),
                motion.correspondences.pairs.size(), Now() - start);
  }
  ValidateCorrespondences(motion.correspondences, motion.reference.num_faces(), scan.num_faces(),
                          correspondences_path.empty() ? out_dir + "/correspondences.json" : correspondences_path);

  start = Now();
  TemplateBvhMotionOptions options;
  options.fps = args.get_double("fps", 25.0);
  options.speed = args.get_double("speed", 1.0);
  options.max_frames = args.get_int("frames", options.max_frames);
  options.retarget.joint_map = ParseBvhJointMap(args.get("bvh-map"), "--bvh-map");
  const std::string up = args.get("bvh-up", "auto");
  if (up != "auto" && up != "y" && up != "z") throw UsageError("--bvh-up: expected auto, y or z, got '" + up + "'");
  options.retarget.up_axis = up == "auto" ? 'a' : up[0];
  BvhRetargetResult retarget;
  auto poses = std::make_shared<std::vector<Pose>>(
      TemplateMotionFromBvh(*body, registration.shape, registration.pose, bvh_path, options, &retarget));
  if (poses->empty()) throw InputError(bvh_path, "no frames to animate");
  std::printf("bvh %s: %.0f fps, up axis %c, units %s (skeleton %.2f m tall), leg-length scale %.4f m/unit, "
              "%zu frames at %.1f fps (%.2f s)\n",
              bvh_path.c_str(), retarget.fps, retarget.up_axis, retarget.unit.c_str(),
              retarget.bvh_height * retarget.metres_per_unit, retarget.translation_scale, poses->size(), options.fps,
              Now() - start);
  std::string unmapped;
  for (const std::string& name : retarget.unmapped) unmapped += (unmapped.empty() ? "" : ", ") + name;
  if (!unmapped.empty()) std::printf("joints without a BVH joint (they follow their parent): %s\n", unmapped.c_str());
  for (const std::string& warning : retarget.warnings) std::fprintf(stderr, "warning: %s: %s\n", bvh_path.c_str(), warning.c_str());
  motion.num_frames = static_cast<int>(poses->size());
  motion.fps = options.fps;
  const std::vector<Eigen::Vector3d> first = JointPositions(body->MakeSkeleton(registration.shape), poses->front());
  const Eigen::Vector3d facing = (first[kTjLeftHip] - first[kTjRightHip]).cross(Eigen::Vector3d::UnitZ());
  motion.front_azimuth_deg = std::atan2(facing.y(), facing.x()) * 180.0 / M_PI;
  const BodyShape shape = registration.shape;
  motion.frame_vertices = [body, poses, shape](int i) { return PosedTemplateMesh(*body, shape, (*poses)[i]).vertices; };
  motion.description = std::to_string(poses->size()) + " frames of " + bvh_path;
  return motion;
}

// The orbit for --render orbit: one turn over the sequence around the moving template (the
// look-at point follows the centre of the template's box, smoothed over half a second), far
// enough for the largest single-frame box; the first camera looks at the front.
std::vector<Camera> OrbitAroundMotion(const TemplateMotion& motion, int width, int height) {
  const int n = motion.num_frames;
  std::vector<Eigen::Vector3d> centre(n);
  double radius = 0.0, mid_height = 0.0;
  for (int i = 0; i < n; ++i) {
    const RowMatrixX3d v = motion.frame_vertices(i);
    const Eigen::Vector3d lo = v.colwise().minCoeff().transpose(), hi = v.colwise().maxCoeff().transpose();
    centre[i] = 0.5 * (lo + hi);
    radius = std::max(radius, 0.5 * (hi - lo).norm());
    mid_height += centre[i].z() / n;
  }
  const int half_window = std::max(1, static_cast<int>(0.25 * motion.fps));
  std::vector<Eigen::Vector3d> smooth(n);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (int k = std::max(0, i - half_window); k <= std::min(n - 1, i + half_window); ++k) sum += centre[k], ++count;
    smooth[i] = sum / count;
    smooth[i].z() = mid_height;
  }
  OrbitPathOptions orbit;
  orbit.width_px = width;
  orbit.height_px = height;
  orbit.vertical_fov_deg = 40.0;
  orbit.num_frames = n;
  orbit.center_in_world = smooth[0];
  orbit.start_angle_deg = motion.front_azimuth_deg;
  const double half_fov = 0.5 * orbit.vertical_fov_deg * M_PI / 180.0 * std::min(1.0, double(width) / height);
  orbit.radius_m = 1.15 * radius / std::sin(half_fov);
  orbit.height_m = mid_height + 0.3 * radius;
  std::vector<Camera> cameras = OrbitPath(orbit);
  for (int i = 0; i < n; ++i) cameras[i].translation -= cameras[i].rotation * (smooth[i] - smooth[0]);
  return cameras;
}

int RunAnimate(const ParsedArgs& args, const Context& context) {
  const double run_start = Now();
  const std::string scan_path = args.get("scan");
  const std::string out_dir = args.get("out");
  const std::string format = Lower(args.get("format", "ply"));
  if (format != "ply" && format != "obj") throw UsageError("--format: expected ply or obj, got '" + format + "'");
  const bool bvh = args.has("bvh");
  if (bvh == args.has("template-sequence")) throw UsageError("give exactly one of --template-sequence DIR and --bvh FILE");
  const std::string render = args.get("render");
  if (args.has("render") && render != "orbit") throw UsageError("--render: expected orbit, got '" + render + "'");
  const int render_width = args.get_int("render-width", 640), render_height = args.get_int("render-height", 480);
  if (render_width < 16 || render_height < 16 || render_width > 8192 || render_height > 8192)
    throw UsageError("--render-width/--render-height: must be within [16, 8192]");

  double start = Now();
  const Mesh scan = ReadMesh(scan_path);
  std::printf("scan %s: %d vertices, %d faces (read in %.2f s)\n", scan_path.c_str(), scan.num_vertices(),
              scan.num_faces(), Now() - start);
  std::filesystem::create_directories(out_dir);
  const TemplateMotion source =
      bvh ? BvhMotionOfTemplate(args, scan_path, scan, out_dir) : SequenceMotion(args, scan_path, scan, out_dir);

  ConfluentMotionOptions options;
  const std::string singularities = args.get("singularities", "intermediate");
  if (singularities != "intermediate" && singularities != "slerp" && singularities != "none")
    throw UsageError("--singularities: expected intermediate, slerp or none, got '" + singularities + "'");
  options.intermediate_reference = singularities == "intermediate" && !args.has("no-intermediate-reference");
  options.slerp_paths = singularities == "slerp";
  ConfluentMotion motion(scan, source.reference, source.correspondences, options, scan_path,
                         args.get("correspondences", out_dir + "/correspondences.json"));
  for (const std::string& warning : motion.setup_summary().warnings)
    std::fprintf(stderr, "warning: %s: %s\n", scan_path.c_str(), warning.c_str());

  std::unique_ptr<PointCacheWriter> cache;
  if (args.has("pc2")) {
    WriteMesh(out_dir + "/rest.ply", scan);
    cache = std::make_unique<PointCacheWriter>(out_dir + "/scan.pc2", scan.num_vertices());
  }
  const bool write_template = args.has("write-template");
  if (write_template) std::filesystem::create_directories(out_dir + "/template");

  // Orbit rendering, frame by frame as the scan is deformed.
  std::unique_ptr<MeshRenderer> renderer;
  std::unique_ptr<VideoWriter> video;
  std::vector<Camera> orbit;
  int mesh_handle = -1;
  RenderRequest request;
  if (!render.empty()) {
    orbit = OrbitAroundMotion(source, render_width, render_height);
    renderer = std::make_unique<MeshRenderer>();
    mesh_handle = renderer->AddMesh(scan, scan_path);
    request.shading.srgb_output = false;  // the scan's colours are display values already
    request.shading.background = Eigen::Vector3d(0.12, 0.12, 0.14);
    request.shading.light_direction_in_world = Eigen::Vector3d(0.3, -0.6, 1.0);
    std::filesystem::create_directories(out_dir + "/orbit");
    VideoWriterOptions video_options;
    video_options.fps = source.fps;
    if (FfmpegAvailable(video_options))
      video = std::make_unique<VideoWriter>(out_dir + "/orbit.mp4", render_width, render_height, video_options);
    else
      std::fprintf(stderr, "warning: ffmpeg not found: no %s/orbit.mp4 (the PNG frames are written)\n", out_dir.c_str());
  }

  const ProgressCallback progress = context.make_progress ? context.make_progress() : ProgressCallback();
  std::set<std::string> warned;
  int singular_frames = 0;
  double template_seconds = 0.0, deform_seconds = 0.0, write_seconds = 0.0, render_seconds = 0.0;
  Mesh output = scan;
  for (int i = 0; i < source.num_frames; ++i) {
    start = Now();
    const RowMatrixX3d template_vertices = source.frame_vertices(i);
    if (template_vertices.rows() != source.reference.num_vertices())
      throw InputError(source.description, "frame " + std::to_string(i) + " has a different vertex count");
    template_seconds += Now() - start;
    DeformSummary summary;
    start = Now();
    output.vertices = motion.Deform(template_vertices, &summary);
    deform_seconds += Now() - start;
    singular_frames += summary.reference_frame >= 0;
    for (const std::string& warning : summary.warnings)
      if (warned.insert(warning.substr(0, 40)).second)
        std::fprintf(stderr, "warning: frame %d: %s\n", i, warning.c_str());
    start = Now();
    WriteMesh(out_dir + "/" + FrameName(i, format), output);
    if (write_template) {
      Mesh posed = source.reference;
      posed.vertices = template_vertices;
      WriteMesh(out_dir + "/template/" + FrameName(i, "ply"), posed);
    }
    if (cache) cache->Append(output.vertices);
    write_seconds += Now() - start;
    if (renderer) {
      start = Now();
      renderer->UpdateVertices(mesh_handle, output.vertices);
      const RenderResult result = renderer->Render(orbit[i], request);
      WriteImage(out_dir + "/orbit/" + FrameName(i, "png"), result.color);
      if (video) video->Write(result.color);
      render_seconds += Now() - start;
    }
    ReportProgress(progress, "animate", i + 1, source.num_frames, "frame " + std::to_string(i));
  }
  if (cache) cache->Finish();
  if (video) {
    start = Now();
    video->Close();
    render_seconds += Now() - start;
  }
  const double n = source.num_frames;
  std::printf("animated %s (%d vertices, %d faces) with %s\n", scan_path.c_str(), scan.num_vertices(),
              scan.num_faces(), source.description.c_str());
  std::printf("pairs %d, factorisation %.3f s, deformation %.2f ms per frame, %d frames with an intermediate "
              "reference\n",
              motion.setup_summary().num_pairs, motion.setup_summary().factor_seconds, 1e3 * deform_seconds / n,
              singular_frames);
  std::printf("per frame: template %.2f ms, deform %.2f ms, write %.2f ms%s; total %.1f s\n", 1e3 * template_seconds / n,
              1e3 * deform_seconds / n, 1e3 * write_seconds / n,
              renderer ? (", render " + std::to_string(1e3 * render_seconds / n).substr(0, 7) + " ms").c_str() : "",
              Now() - run_start);
  std::printf("wrote %s/%s .. %s%s\n", out_dir.c_str(), FrameName(0, format).c_str(),
              FrameName(source.num_frames - 1, format).c_str(), cache ? " and scan.pc2 + rest.ply" : "");
  if (renderer)
    std::printf("orbit: %s/orbit/%s .. %s%s\n", out_dir.c_str(), FrameName(0, "png").c_str(),
                FrameName(source.num_frames - 1, "png").c_str(), video ? (" and " + out_dir + "/orbit.mp4").c_str() : "");
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
