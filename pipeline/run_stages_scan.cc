// The scan-side stages of `confluent run`: registration and correspondences, Confluent Motion,
// and the 3D-video render.

#include <algorithm>
#include <cmath>
#include <memory>
#include <filesystem>

#include "pipeline/run_stages.h"
#include "pipeline/scan_correspondence.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/parallel.h"
#include "core/video_writer.h"
#include "deform/confluent_motion.h"
#include "deform/correspondences.h"
#include "refine/photo_refinement.h"
#include "refine/silhouette_refinement.h"
#include "render/camera_path.h"
#include "render/projective_texture.h"
#include "tracking/motion_io.h"

namespace confluent {
namespace fs = std::filesystem;

StageReport RunCorrespondenceStage(const RunInputs& inputs, const BodyTemplate& body, const BodyShape& shape,
                                   TimingLog* timings) {
  StageReport report("correspondences");
  const double start = NowSeconds();
  const std::string out_path = inputs.folder.Path("correspondences.json");
  const std::string reference_path = inputs.folder.Path("template_reference.ply");
  if (fs::exists(out_path) && fs::exists(reference_path)) {
    report.skipped = 1;
    return report;
  }
  // The template in the scan's reference pose, with the tracked shape: the rotations of the
  // tracked frames are then measured from the pose the scan stands in.
  ScanCorrespondenceOptions options;
  options.known_shape = shape;
  options.given_path = inputs.correspondences_path;
  try {
    const PosesFile tracked = ReadPosesJson(inputs.folder.Path("poses.json"), body);
    if (!tracked.frames.empty()) options.first_tracked_pose = tracked.frames.front().pose;
  } catch (const InputError&) {
    // No readable poses.json (a shard): registration without the first tracked pose.
  }
  const ScanCorrespondence result = CorrespondTemplateToScan(body, *inputs.scan, inputs.scan_path, options);
  char residual[64];
  std::snprintf(residual, sizeof residual, "template registered to the scan: rms residual %.2f cm",
                100.0 * result.registration.rms_residual_m);
  report.notes.push_back(residual);
  for (const std::string& warning : result.registration.warnings) report.notes.push_back("warning: " + warning);
  report.notes.push_back(std::to_string(result.correspondences.pairs.size()) +
                         (result.given ? " correspondences given: " + inputs.correspondences_path
                                       : std::string(" correspondences placed automatically")));
  WriteScanCorrespondence(result, body, inputs.scan_path, reference_path, "template_reference.ply", out_path);
  report.computed = 1;
  report.seconds = NowSeconds() - start;
  timings->Add("correspondences", -1, report.seconds);
  timings->Save();
  return report;
}

StageReport RunDeformStage(const RunInputs& inputs, const ProgressCallback& progress, TimingLog* timings) {
  StageReport report("deform");
  const double start = NowSeconds();
  const RunFolder& folder = inputs.folder;
  std::vector<int> todo;
  for (int frame = inputs.frames.first; frame < inputs.frames.end; ++frame) {
    if (fs::exists(folder.ScanPath(frame))) ++report.skipped;
    else todo.push_back(frame);
  }
  if (todo.empty()) return report;

  const Mesh& scan = *inputs.scan;
  const std::string reference_path = folder.Path("template_reference.ply");
  const std::string correspondences_path = folder.Path("correspondences.json");
  const Mesh reference = ReadMesh(reference_path);
  const Correspondences correspondences = ReadCorrespondences(correspondences_path);
  const double factor_start = NowSeconds();
  ConfluentMotion motion(scan, reference, correspondences, {}, inputs.scan_path, correspondences_path);
  timings->Add("deform_factor", -1, NowSeconds() - factor_start);
  fs::create_directories(folder.Path("scan"));
  // Silhouette refinement against the cameras the run uses.
  std::unique_ptr<SilhouetteRefiner> refiner;
  // Photo-consistency refinement, then a few silhouette rounds to put the outline back where the
  // moves along the normals shifted it.
  std::unique_ptr<PhotoRefiner> photo_refiner;
  const int outline_rounds = std::min(6, inputs.refine_iterations);
  std::vector<Camera> used_cameras;
  std::vector<int> used_indices;
  if (inputs.refine_silhouettes) {
    const double refine_start = NowSeconds();
    SilhouetteRefinementOptions refine_options;
    refine_options.threads = inputs.threads;
    refine_options.iterations = inputs.refine_iterations;
    refiner = std::make_unique<SilhouetteRefiner>(scan, refine_options);
    if (inputs.refine_photo) {
      PhotoRefinementOptions photo_options;
      photo_options.threads = inputs.threads;
      photo_refiner = std::make_unique<PhotoRefiner>(scan, photo_options);
    }
    timings->Add("refine_factor", -1, NowSeconds() - refine_start);
    const Rig& rig = inputs.capture->rig();
    used_cameras = inputs.cameras.UsedCameras(rig);
    used_indices = inputs.cameras.used();
  }
  double iou_before = 0.0, iou_after = 0.0;
  int iou_views = 0;
  double flow_before = 0.0, flow_after = 0.0;
  int flow_frames = 0;

  auto template_vertices = [&](int frame) {
    const std::string path = folder.TemplatePath(frame);
    if (!fs::exists(path)) throw InputError(path, "posed template missing (the tracking stage did not finish this frame)");
    Mesh posed = ReadMesh(path);
    if (posed.vertices.rows() != reference.vertices.rows())
      throw InputError(path, "the template has " + std::to_string(posed.vertices.rows()) + " vertices, the reference " +
                                 std::to_string(reference.vertices.rows()));
    return posed.vertices;
  };
  int done = 0;
  int previous = -2;
  std::vector<int> singular_frames;
  for (int frame : todo) {
    // Sign consistency and the intermediate reference follow the previous frame: replay it when
    // this invocation starts in the middle of the sequence.
    if (previous != frame - 1 && frame > 0 && fs::exists(folder.TemplatePath(frame - 1))) motion.Deform(template_vertices(frame - 1));
    const double frame_start = NowSeconds();
    DeformSummary summary;
    Mesh animated = scan;
    animated.vertices = motion.Deform(template_vertices(frame), &summary);
    timings->Add("deform", frame, NowSeconds() - frame_start);
    std::vector<Image> masks;
    std::vector<double> iou_after_frame;  // per used camera, after the last refinement
    if (refiner) {
      const double refine_start = NowSeconds();
      masks.resize(used_indices.size());
      ParallelFor(static_cast<int>(used_indices.size()), inputs.threads, [&](int i) {
        const std::string path = RunMaskPath(inputs, used_indices[i], frame);
        if (!fs::exists(path)) throw InputError(path, "silhouette missing (the silhouette stage did not finish this frame)");
        masks[i] = ReadMaskFile(path);
      });
      SilhouetteRefinementSummary refined;
      animated.vertices = refiner->Refine(animated.vertices, used_cameras, masks, &refined);
      for (std::size_t i = 0; i < used_cameras.size(); ++i)
        if (!std::isnan(refined.iou_before[i])) iou_before += refined.iou_before[i], ++iou_views;
      iou_after_frame = refined.iou_after;
      timings->Add("refine", frame, NowSeconds() - refine_start);
    }
    if (photo_refiner) {
      const double photo_start = NowSeconds();
      const std::vector<Image> images = inputs.capture->ReadFrames(used_indices, frame, inputs.threads);
      PhotoRefinementSummary photo;
      animated.vertices = photo_refiner->Refine(animated.vertices, used_cameras, images, &photo);
      if (photo.rounds > 0) flow_before += photo.first_flow_px, flow_after += photo.last_flow_px, ++flow_frames;
      SilhouetteRefinementSummary outline;
      animated.vertices = refiner->Refine(animated.vertices, used_cameras, masks, &outline, outline_rounds);
      iou_after_frame = outline.iou_after;
      timings->Add("photo_refine", frame, NowSeconds() - photo_start);
    }
    for (double iou : iou_after_frame)
      if (!std::isnan(iou)) iou_after += iou;
    WriteMesh(folder.ScanPath(frame), animated);
    if (summary.singular) singular_frames.push_back(frame);
    previous = frame;
    ++report.computed;
    ReportProgress(progress, "deform", ++done, todo.size(), "frame " + std::to_string(frame));
  }
  if (iou_views > 0) {
    char line[160];
    std::snprintf(line, sizeof(line), "%s: scan IoU in the used cameras %.4f -> %.4f (mean over %d views)",
                  photo_refiner ? "silhouette and photo refinement" : "silhouette refinement", iou_before / iou_views,
                  iou_after / iou_views, iou_views);
    report.notes.push_back(line);
  }
  if (flow_frames > 0) {
    char line[200];
    std::snprintf(line, sizeof(line),
                  "photo refinement: mean flow between neighbouring cameras through the scan %.3f px -> %.3f px (before "
                  "the last round; mean over %d frames)", flow_before / flow_frames, flow_after / flow_frames, flow_frames);
    report.notes.push_back(line);
  }
  if (!singular_frames.empty())
    report.notes.push_back(std::to_string(singular_frames.size()) +
                           " frame(s) near a 180-degree rotation used an intermediate reference (report section 4.3), frames " +
                           std::to_string(singular_frames.front()) + " to " + std::to_string(singular_frames.back()));
  timings->Save();
  report.seconds = NowSeconds() - start;
  return report;
}

namespace {

// A point the orbit looks at: the centre of the used cameras' ring, at mid-body height.
Eigen::Vector3d RingCentre(const std::vector<Camera>& cameras) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Camera& camera : cameras) sum += camera.center_in_world();
  Eigen::Vector3d centre = sum / std::max<std::size_t>(1, cameras.size());
  centre.z() = 0.95;
  return centre;
}

}  // namespace

StageReport RunRenderStage(const RunInputs& inputs, const RenderStageOptions& options, const ProgressCallback& progress,
                           TimingLog* timings) {
  StageReport report("render");
  const double start = NowSeconds();
  const RunFolder& folder = inputs.folder;
  const Capture& capture = *inputs.capture;
  const Rig& rig = capture.rig();
  const bool use_scan = inputs.scan != nullptr;
  auto geometry_path = [&](int frame) { return use_scan ? folder.ScanPath(frame) : folder.TemplatePath(frame); };

  const std::vector<int> used = inputs.cameras.used();
  const std::vector<Camera> used_cameras = inputs.cameras.UsedCameras(rig);
  OrbitPathOptions orbit = OrbitAroundCameras(used_cameras, RingCentre(used_cameras));
  orbit.num_frames = capture.num_frames();  // the whole capture is one turn, so shards agree
  orbit.width_px = options.width;
  orbit.height_px = options.height;
  const std::vector<Camera> path = OrbitPath(orbit);

  std::vector<int> todo;
  for (int frame = inputs.frames.first; frame < inputs.frames.end; ++frame) {
    if (fs::exists(folder.RenderPath(options.view, frame))) {
      ++report.skipped;
    } else if (!fs::exists(geometry_path(frame))) {
      report.notes.push_back("missing geometry, frame not rendered: " + geometry_path(frame));
    } else {
      todo.push_back(frame);
    }
  }
  if (!todo.empty()) {
    // Topology and colours: the scan's own, or the posed template's.
    ProjectiveTexturer texturer(use_scan ? *inputs.scan : ReadMesh(geometry_path(todo.front())));
    fs::create_directories(folder.Path("renders/" + options.view));
    int done = 0;
    for (int frame : todo) {
      const double frame_start = NowSeconds();
      const Mesh mesh = ReadMesh(geometry_path(frame));
      const std::vector<Image> images = capture.ReadFrames(used, frame, inputs.threads);
      std::vector<Image> masks(used.size());
      ParallelFor(static_cast<int>(used.size()), inputs.threads, [&](int i) {
        const std::string mask_path = RunMaskPath(inputs, used[i], frame);
        if (fs::exists(mask_path)) masks[i] = ReadMaskFile(mask_path);
      });
      texturer.SetFrame(mesh.vertices, used_cameras, images, masks);
      const RenderResult result = texturer.Render(path[frame]);
      WriteImage(folder.RenderPath(options.view, frame), result.color);
      timings->Add("render", frame, NowSeconds() - frame_start);
      ++report.computed;
      ReportProgress(progress, "render", ++done, todo.size(), "frame " + std::to_string(frame));
    }
    timings->Save();
  }
  // The video over every rendered frame of the capture, in order.
  std::vector<std::string> frames;
  for (int frame = 0; frame < capture.num_frames(); ++frame)
    if (fs::exists(folder.RenderPath(options.view, frame))) frames.push_back(folder.RenderPath(options.view, frame));
  const std::string video = folder.VideoPath(options.view);
  if (static_cast<int>(frames.size()) < capture.num_frames()) {
    report.notes.push_back(std::to_string(capture.num_frames() - frames.size()) +
                           " frame(s) of the capture not rendered yet: " + video + " is written once all are");
  } else if (report.computed > 0 || !fs::exists(video)) {
    VideoWriterOptions video_options;
    video_options.fps = inputs.fps;
    if (!FfmpegAvailable(video_options)) {
      report.notes.push_back("ffmpeg not found: no " + video + " (the PNG frames are written)");
    } else {
      const double video_start = NowSeconds();
      VideoWriter writer(video, options.width, options.height, video_options);
      for (const std::string& file : frames) writer.Write(ReadImage(file));
      writer.Close();
      timings->Add("video", -1, NowSeconds() - video_start);
      report.notes.push_back("video: " + video + " (" + std::to_string(frames.size()) + " frames)");
    }
  }
  timings->Save();
  report.seconds = NowSeconds() - start;
  return report;
}

}  // namespace confluent
