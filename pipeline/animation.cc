#include "pipeline/animation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>

#include "core/bvh_retarget.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/video_writer.h"
#include "deform/point_cache.h"
#include "pipeline/frame_range.h"
#include "pipeline/run_folder.h"
#include "pipeline/scan_correspondence.h"
#include "render/camera_path.h"
#include "render/renderer.h"
#include "tracking/body_template.h"
#include "tracking/scan_registration.h"

namespace confluent {
namespace {

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

std::string FrameName(int frame, const std::string& extension) { return FrameStem(frame) + "." + extension; }

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

}  // namespace

// --template-sequence DIR: meshes from files.
TemplateMotion SequenceMotion(const SequenceMotionOptions& options, const std::string& scan_path, const Mesh& scan,
                              const std::string& out_dir, AnimationLog* log) {
  const std::string& sequence_dir = options.dir;
  const std::string& correspondences_path = options.correspondences_path;
  if (correspondences_path.empty()) throw UsageError("--template-sequence needs --correspondences C");
  const std::vector<std::string> frames = SequenceFiles(sequence_dir);
  const int reference_frame = options.reference_frame;
  if (reference_frame < 0 || reference_frame >= static_cast<int>(frames.size()))
    throw UsageError("--reference-frame: must be in [0, " + std::to_string(frames.size() - 1) + "], got " +
                     std::to_string(reference_frame));
  TemplateMotion motion;
  motion.reference = ReadMesh(frames[reference_frame]);
  motion.correspondences = ReadCorrespondences(correspondences_path);
  ValidateCorrespondences(motion.correspondences, motion.reference.num_faces(), scan.num_faces(), correspondences_path);
  if (options.augment) {
    const std::size_t given = motion.correspondences.pairs.size();
    motion.correspondences = AugmentCorrespondences(motion.reference, scan, motion.correspondences);
    motion.correspondences.scan_path = std::filesystem::absolute(scan_path).string();
    WriteCorrespondences(out_dir + "/correspondences.json", motion.correspondences);
    log->info.push_back("augmented " + std::to_string(given) + " given pairs to " +
                        std::to_string(motion.correspondences.pairs.size()) + " (written to " + out_dir +
                        "/correspondences.json)");
  }
  motion.num_frames = static_cast<int>(frames.size());
  motion.fps = options.fps;
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
TemplateMotion BvhMotionOfTemplate(const BvhMotionSourceOptions& source_options, const std::string& scan_path,
                                   const Mesh& scan, const std::string& out_dir, AnimationLog* log) {
  const std::string& bvh_path = source_options.bvh_path;
  const std::string& correspondences_path = source_options.correspondences_path;
  auto body = std::make_shared<BodyTemplate>();
  ScanRegistration registration;
  TemplateMotion motion;
  double start = NowSeconds();
  if (correspondences_path.empty()) {
    // Automatic: register the template to the scan, place the pairs, keep both for re-runs.
    const ScanCorrespondence result = CorrespondTemplateToScan(*body, scan, scan_path, ScanCorrespondenceOptions());
    registration = result.registration;
    motion.reference = result.reference;
    motion.correspondences = result.correspondences;
    char line[256];
    std::snprintf(line, sizeof line,
                  "template registered to the scan: rms residual %.4g (scan units, %.3g m per unit), %zu correspondences "
                  "placed automatically (%.2f s)",
                  registration.rms_residual_m, registration.metres_per_unit, motion.correspondences.pairs.size(),
                  NowSeconds() - start);
    log->info.push_back(line);
    for (const std::string& warning : registration.warnings) log->warnings.push_back(scan_path + ": " + warning);
    const std::string written = out_dir + "/correspondences.json";
    WriteScanCorrespondence(result, *body, scan_path, out_dir + "/template_reference.ply", "template_reference.ply",
                            written);
    log->info.push_back("written to " + written);
  } else {
    registration = ReadTemplateRegistration(correspondences_path, *body);
    motion.correspondences = ReadCorrespondences(correspondences_path);
    motion.reference = body->PosedMesh(registration.shape, registration.pose);
    char line[512];
    std::snprintf(line, sizeof line, "template registration from %s: %zu pairs (%.2f s)", correspondences_path.c_str(),
                  motion.correspondences.pairs.size(), NowSeconds() - start);
    log->info.push_back(line);
  }
  ValidateCorrespondences(motion.correspondences, motion.reference.num_faces(), scan.num_faces(),
                          correspondences_path.empty() ? out_dir + "/correspondences.json" : correspondences_path);

  start = NowSeconds();
  const TemplateBvhMotionOptions& options = source_options.motion;
  BvhRetargetResult retarget;
  auto poses = std::make_shared<std::vector<Pose>>(
      TemplateMotionFromBvh(*body, registration.shape, registration.pose, bvh_path, options, &retarget));
  if (poses->empty()) throw InputError(bvh_path, "no frames to animate");
  char line[512];
  std::snprintf(line, sizeof line,
                "bvh %s: %.0f fps, up axis %c, units %s (skeleton %.2f m tall), leg-length scale %.4f m/unit, "
                "%zu frames at %.1f fps (%.2f s)",
                bvh_path.c_str(), retarget.fps, retarget.up_axis, retarget.unit.c_str(),
                retarget.bvh_height * retarget.metres_per_unit, retarget.translation_scale, poses->size(), options.fps,
                NowSeconds() - start);
  log->info.push_back(line);
  std::string unmapped;
  for (const std::string& name : retarget.unmapped) unmapped += (unmapped.empty() ? "" : ", ") + name;
  if (!unmapped.empty()) log->info.push_back("joints without a BVH joint (they follow their parent): " + unmapped);
  std::string turns;
  for (const auto& [side, degrees] : retarget.elbow_turns_deg) {
    std::snprintf(line, sizeof line, "%s%s %+.0f", turns.empty() ? "" : ", ", side.c_str(), degrees);
    turns += line;
  }
  if (!turns.empty())
    log->info.push_back("arms turned about themselves so that the elbows bend about the template's hinge (degrees): " +
                        turns);
  for (const std::string& warning : retarget.warnings) log->warnings.push_back(bvh_path + ": " + warning);
  motion.num_frames = static_cast<int>(poses->size());
  motion.fps = options.fps;
  const std::vector<Eigen::Vector3d> first = JointPositions(body->MakeSkeleton(registration.shape), poses->front());
  const Eigen::Vector3d facing = (first[kJointLeftHip] - first[kJointRightHip]).cross(Eigen::Vector3d::UnitZ());
  motion.front_azimuth_deg = std::atan2(facing.y(), facing.x()) * 180.0 / M_PI;
  const BodyShape shape = registration.shape;
  motion.frame_vertices = [body, poses, shape](int i) { return PosedTemplateMesh(*body, shape, (*poses)[i]).vertices; };
  motion.description = std::to_string(poses->size()) + " frames of " + bvh_path;
  return motion;
}

AnimationSummary AnimateScan(const Mesh& scan, const std::string& scan_path, const TemplateMotion& source,
                             const std::string& out_dir, const AnimationOptions& options,
                             const ProgressCallback& progress) {
  const double run_start = NowSeconds();
  AnimationSummary result;
  AnimationLog* log = &result.log;
  const std::string& format = options.format;
  ConfluentMotion motion(scan, source.reference, source.correspondences, options.motion, scan_path,
                         options.correspondences_source);
  for (const std::string& warning : motion.setup_summary().warnings) log->warnings.push_back(scan_path + ": " + warning);

  std::unique_ptr<PointCacheWriter> cache;
  if (options.pc2) {
    WriteMesh(out_dir + "/rest.ply", scan);
    cache = std::make_unique<PointCacheWriter>(out_dir + "/scan.pc2", scan.num_vertices());
  }
  const bool write_template = options.write_template;
  if (write_template) std::filesystem::create_directories(out_dir + "/template");

  // Orbit rendering, frame by frame as the scan is deformed.
  std::unique_ptr<MeshRenderer> renderer;
  std::unique_ptr<VideoWriter> video;
  std::vector<Camera> orbit;
  int mesh_handle = -1;
  RenderRequest request;
  if (options.render_orbit) {
    const int render_width = options.render_width, render_height = options.render_height;
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
      log->warnings.push_back("ffmpeg not found: no " + out_dir + "/orbit.mp4 (the PNG frames are written)");
  }

  std::set<std::string> warned;
  int singular_frames = 0;
  double template_seconds = 0.0, deform_seconds = 0.0, write_seconds = 0.0, render_seconds = 0.0;
  Mesh output = scan;
  for (int i = 0; i < source.num_frames; ++i) {
    double start = NowSeconds();
    const RowMatrixX3d template_vertices = source.frame_vertices(i);
    if (template_vertices.rows() != source.reference.num_vertices())
      throw InputError(source.description, "frame " + std::to_string(i) + " has a different vertex count");
    template_seconds += NowSeconds() - start;
    DeformSummary summary;
    start = NowSeconds();
    output.vertices = motion.Deform(template_vertices, &summary);
    deform_seconds += NowSeconds() - start;
    singular_frames += summary.reference_frame >= 0;
    for (const std::string& warning : summary.warnings)
      if (warned.insert(warning.substr(0, 40)).second)
        log->warnings.push_back("frame " + std::to_string(i) + ": " + warning);
    start = NowSeconds();
    WriteMesh(out_dir + "/" + FrameName(i, format), output);
    if (write_template) {
      Mesh posed = source.reference;
      posed.vertices = template_vertices;
      WriteMesh(out_dir + "/template/" + FrameName(i, "ply"), posed);
    }
    if (cache) cache->Append(output.vertices);
    write_seconds += NowSeconds() - start;
    if (renderer) {
      start = NowSeconds();
      renderer->UpdateVertices(mesh_handle, output.vertices);
      const RenderResult result = renderer->Render(orbit[i], request);
      WriteImage(out_dir + "/orbit/" + FrameName(i, "png"), result.color);
      if (video) video->Write(result.color);
      render_seconds += NowSeconds() - start;
    }
    ReportProgress(progress, "animate", i + 1, source.num_frames, "frame " + std::to_string(i));
  }
  if (cache) cache->Finish();
  if (video) {
    const double start = NowSeconds();
    video->Close();
    render_seconds += NowSeconds() - start;
  }
  const double n = source.num_frames;
  char line[512];
  std::snprintf(line, sizeof line, "animated %s (%d vertices, %d faces) with %s", scan_path.c_str(), scan.num_vertices(),
                scan.num_faces(), source.description.c_str());
  log->info.push_back(line);
  std::snprintf(line, sizeof line,
                "pairs %d, factorisation %.3f s, deformation %.2f ms per frame, %d frames with an intermediate reference",
                motion.setup_summary().num_pairs, motion.setup_summary().factor_seconds, 1e3 * deform_seconds / n,
                singular_frames);
  log->info.push_back(line);
  std::snprintf(line, sizeof line, "per frame: template %.2f ms, deform %.2f ms, write %.2f ms%s; total %.1f s",
                1e3 * template_seconds / n, 1e3 * deform_seconds / n, 1e3 * write_seconds / n,
                renderer ? (", render " + std::to_string(1e3 * render_seconds / n).substr(0, 7) + " ms").c_str() : "",
                NowSeconds() - run_start);
  log->info.push_back(line);
  log->info.push_back("wrote " + out_dir + "/" + FrameName(0, format) + " .. " + FrameName(source.num_frames - 1, format) +
                      (cache ? " and scan.pc2 + rest.ply" : ""));
  if (renderer)
    log->info.push_back("orbit: " + out_dir + "/orbit/" + FrameName(0, "png") + " .. " +
                        FrameName(source.num_frames - 1, "png") + (video ? " and " + out_dir + "/orbit.mp4" : ""));
  result.frames = source.num_frames;
  result.singular_frames = singular_frames;
  return result;
}

}  // namespace confluent
