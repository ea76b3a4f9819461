// The scan-side stages of `confluent run`: registration and correspondences, and Confluent Motion
// with its refinements.

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <memory>
#include <optional>

#include "pipeline/run_stages.h"
#include "pipeline/orbit_frames.h"
#include "pipeline/first_pose_seam.h"
#include "pipeline/frame_refinement.h"
#include "pipeline/scan_correspondence.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/parallel.h"
#include "deform/confluent_motion.h"
#include "deform/correspondences.h"
#include "silhouette/overlap.h"
#include "tracking/motion_io.h"
#include "tracking/scan_registration.h"

namespace confluent {
namespace fs = std::filesystem;

namespace {

// The mean IoU over the tracking cameras of the template in `pose` with one frame's `masks`
// (TrackingMasks), at the tracker's resolution.
double TrackingOverlap(const RunInputs& inputs, const BodyTemplate& body, const BodyShape& shape,
                       const TemplatePose& pose, const std::vector<Image>& masks) {
  return MeanSilhouetteIoU(
      SilhouetteIoUs(body.PosedMesh(shape, pose), inputs.capture->rig(), masks, {}, inputs.tracker.iou_downscale));
}

}  // namespace

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
  std::vector<Image> first_masks;
  try {
    const PosesFile tracked = ReadPosesJson(inputs.folder.Path("poses.json"), body);
    if (!tracked.frames.empty() && tracked.frames.front().frame == 0) {
      options.first_tracked_pose = tracked.frames.front().pose;
      first_masks = TrackingMasks(inputs, 0);
    }
  } catch (const InputError&) {
    // No readable poses.json, or frame 0's masks are gone: the residuals alone decide.
  }
  if (!first_masks.empty()) {
    options.first_frame_overlap = [&](const TemplatePose& pose) {
      return TrackingOverlap(inputs, body, shape, pose, first_masks);
    };
  }
  // Without frame 0 (a first shard that starts later) the registration goes without the first
  // tracked pose: the seam it may record eases frames from 0 on.
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

namespace {

// The seam of a scan in the first tracked frame's pose whose reference is not that frame's
// template (its registration records the first tracked pose), with the tracked poses and shape.
struct RunSeam {
  FirstPoseSeam seam;
  PosesFile tracked;
};

std::optional<RunSeam> ReadRunSeam(const RunInputs& inputs, const BodyTemplate& body,
                                   const std::string& correspondences_path) {
  if (!HasTemplateRegistration(correspondences_path)) return std::nullopt;  // given correspondences
  const ScanRegistration registration = ReadTemplateRegistration(correspondences_path, body);
  if (!registration.first_tracked_pose) return std::nullopt;
  RunSeam run{{registration.pose, *registration.first_tracked_pose, FirstPoseSeamFrames(inputs.fps)},
              ReadPosesJson(inputs.folder.Path("poses.json"), body)};
  auto tracked = [&](int frame) -> const TemplatePose* {
    for (const TrackedFrame& f : run.tracked.frames)
      if (f.frame == frame) return &f.pose;
    return nullptr;
  };
  // Each frame's masks are read once (FirstPoseSeamEnd asks two poses per frame).
  int masks_frame = -1;
  std::vector<Image> masks;
  auto overlap = [&](int frame, const TemplatePose& pose) -> std::optional<double> {
    if (frame != masks_frame) {
      try {
        masks = TrackingMasks(inputs, frame);
      } catch (const InputError&) {
        return std::nullopt;  // a shard's masks not there yet: the seam eases as planned
      }
      masks_frame = frame;
    }
    return TrackingOverlap(inputs, body, run.tracked.shape, pose, masks);
  };
  run.seam.tracked_from = FirstPoseSeamEnd(body, run.seam, tracked, overlap);
  return run;
}

}  // namespace

StageReport RunDeformStage(const RunInputs& inputs, const BodyTemplate& body, const ProgressCallback& progress,
                           TimingLog* timings, const RenderStageOptions* render) {
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
  const std::optional<RunSeam> seam = ReadRunSeam(inputs, body, correspondences_path);
  if (seam && seam->seam.tracked_from < seam->seam.frames)
    report.notes.push_back("the first frames ease from the scan's pose into the tracked ones up to frame " +
                           std::to_string(seam->seam.tracked_from) +
                           ", where the tracked pose explains the silhouettes better than the eased one");
  const double factor_start = NowSeconds();
  ConfluentMotion motion(scan, reference, correspondences, {}, inputs.scan_path, correspondences_path);
  timings->Add("deform_factor", -1, NowSeconds() - factor_start);
  fs::create_directories(folder.Path("scan"));
  // Silhouette refinement against the cameras the run uses, then photo consistency. Without
  // keyframes every frame's refinement is independent of the others': two consecutive frames are
  // refined side by side, each by its own refiner (the same partitions of the work as one frame
  // alone, so the same result), which fills the cores that one frame's serial steps leave idle.
  std::vector<std::unique_ptr<FrameRefinement>> refiners;
  const std::vector<int> used_indices = inputs.cameras.used();
  if (inputs.refine_silhouettes) {
    const double refine_start = NowSeconds();
    FrameRefinementOptions options;
    options.photo = inputs.refine_photo;
    options.silhouette_rounds = inputs.refine_iterations;
    options.outline_rounds = std::min(options.outline_rounds, inputs.refine_iterations);
    options.carried_silhouette_rounds = std::min(options.carried_silhouette_rounds, inputs.refine_iterations);
    options.threads = inputs.threads;
    options.keyframe_interval = inputs.refine_keyframes;
    options.photo_rounds = inputs.photo_rounds;
    options.photo_full_resolution_rounds = inputs.photo_full_resolution_rounds;
    const int lanes = inputs.refine_keyframes == 1 && inputs.threads >= 2 && todo.size() >= 2 ? 2 : 1;
    refiners.resize(lanes);
    const std::vector<Camera> used_cameras = inputs.cameras.UsedCameras(inputs.capture->rig());
    ParallelFor(lanes, lanes, [&](int lane) {
      refiners[lane] = std::make_unique<FrameRefinement>(scan, used_cameras, options);
    });
    timings->Add("refine_factor", -1, NowSeconds() - refine_start);
  }
  FrameRefinement* const refinement = refiners.empty() ? nullptr : refiners.front().get();
  double iou_before = 0.0, iou_after = 0.0;
  int iou_views = 0;
  double flow_before = 0.0, flow_after = 0.0;
  int flow_frames = 0, carried_frames = 0;

  auto template_vertices = [&](int frame) {
    const std::string path = folder.TemplatePath(frame);
    if (!fs::exists(path)) throw InputError(path, "posed template missing (the tracking stage did not finish this frame)");
    Mesh posed = ReadMesh(path);
    if (posed.vertices.rows() != reference.vertices.rows())
      throw InputError(path, "the template has " + std::to_string(posed.vertices.rows()) + " vertices, the reference " +
                                 std::to_string(reference.vertices.rows()));
    if (seam && FirstPoseSeamWeight(seam->seam, frame) > 0.0) {
      const auto tracked = std::find_if(seam->tracked.frames.begin(), seam->tracked.frames.end(),
                                        [&](const TrackedFrame& f) { return f.frame == frame; });
      if (tracked == seam->tracked.frames.end())
        throw InputError(folder.Path("poses.json"), "frame " + std::to_string(frame) + " is not tracked");
      ApplyFirstPoseSeam(body, seam->tracked.shape, seam->seam, tracked->pose, frame, &posed.vertices);
    }
    return posed.vertices;
  };
  // The used cameras' masks and images at `frame`.
  auto read_masks = [&](int frame) {
    std::vector<Image> masks(used_indices.size());
    ParallelFor(static_cast<int>(used_indices.size()), inputs.threads, [&](int i) {
      const std::string path = RunMaskPath(inputs, used_indices[i], frame);
      if (!fs::exists(path)) throw InputError(path, "silhouette missing (the silhouette stage did not finish this frame)");
      masks[i] = ReadMaskFile(path);
    });
    return masks;
  };
  auto read_images = [&](int frame) {
    return inputs.refine_photo ? inputs.capture->ReadFrames(used_indices, frame, inputs.threads) : std::vector<Image>();
  };
  // The 3D video's frames, drawn here from the photo refinement's images (the render stage would
  // decode them again). Without a GL context the render stage is left to report it.
  std::unique_ptr<OrbitFrames> orbit;
  bool orbit_failed = render == nullptr;
  int rendered = 0;
  auto orbit_frames = [&]() -> OrbitFrames* {
    if (!orbit && !orbit_failed) {
      try {
        orbit = std::make_unique<OrbitFrames>(inputs, *render, scan);
      } catch (const RenderContextError&) {
        orbit_failed = true;
      }
    }
    return orbit.get();
  };
  // One frame on its way through the stage.
  struct FrameWork {
    int frame = 0;
    Mesh animated;
    DeformSummary deform;
    std::vector<Image> masks, images;
    double masks_read = 0.0, images_read = 0.0;
    FrameRefinementSummary refined;
  };
  int done = 0;
  int previous = -2;
  std::vector<int> singular_frames;
  for (std::size_t next = 0; next < todo.size();) {
    // This batch: the next frame, and the one after it where a second refiner can take it.
    std::vector<FrameWork> batch(1);
    batch[0].frame = todo[next];
    if (refiners.size() == 2 && next + 1 < todo.size() && todo[next + 1] == todo[next] + 1) {
      batch.emplace_back();
      batch[1].frame = todo[next + 1];
    }
    next += batch.size();
    const int frame = batch[0].frame;
    if (previous != frame - 1) {
      // The deformation carries state through every frame before (quaternion signs kept
      // continuous over the whole sequence, the intermediate reference, SLERP paths), the
      // refinement through the frames since the keyframe. Where this invocation starts in the
      // middle, or skips finished frames, both chains are carried on from where they stand (frame
      // 0, or the frame after `previous`) so that the scans are those of one uninterrupted run.
      // Without the templates in between (shards run side by side) the deformation starts from
      // the previous frame where it is tracked, else afresh, and the refinement from the frame's
      // own deformation.
      const int chained = previous >= 0 ? previous + 1 : 0;
      int first = frame;  // the first frame replayed with its refinement
      if (refinement)
        while (first > chained && !refinement->IsKeyframe(first)) --first;
      auto tracked_from = [&](int begin) {
        for (int earlier = std::max(0, begin); earlier < frame; ++earlier)
          if (!fs::exists(folder.TemplatePath(earlier))) return false;
        return true;
      };
      if (tracked_from(chained)) {
        for (int earlier = chained; earlier < first; ++earlier) motion.Deform(template_vertices(earlier));
      } else {
        if (!tracked_from(first - 1)) first = frame;
        if (first > 0 && fs::exists(folder.TemplatePath(first - 1))) motion.Deform(template_vertices(first - 1));
      }
      for (int earlier = first; earlier < frame; ++earlier)
        refinement->Refine(earlier, motion.Deform(template_vertices(earlier)), read_masks(earlier), read_images(earlier));
    }
    for (FrameWork& work : batch) {
      const double frame_start = NowSeconds();
      work.animated = scan;
      work.animated.vertices = motion.Deform(template_vertices(work.frame), &work.deform);
      timings->Add("deform", work.frame, NowSeconds() - frame_start);
      if (!refinement) continue;
      const double read_start = NowSeconds();
      work.masks = read_masks(work.frame);
      work.masks_read = NowSeconds() - read_start;
      work.images = read_images(work.frame);
      work.images_read = NowSeconds() - read_start - work.masks_read;
    }
    if (refinement) {
      const double refine_start = NowSeconds();
      // A frame whose refinement fails does not cost the other its result: that one is written first.
      std::vector<std::exception_ptr> failures(batch.size());
      ParallelFor(static_cast<int>(batch.size()), static_cast<int>(batch.size()), [&](int lane) {
        FrameWork& work = batch[lane];
        try {
          work.animated.vertices =
              refiners[lane]->Refine(work.frame, work.animated.vertices, work.masks, work.images, &work.refined);
        } catch (...) {
          failures[lane] = std::current_exception();
        }
      });
      for (std::size_t lane = 0; lane < batch.size(); ++lane)
        if (failures[lane]) {
          for (std::size_t other = 0; other < lane; ++other) WriteMesh(folder.ScanPath(batch[other].frame), batch[other].animated);
          std::rethrow_exception(failures[lane]);
        }
      // Frames refined side by side: each is charged its share of the batch's wall time.
      double lane_seconds = 0.0;
      for (const FrameWork& work : batch) lane_seconds += work.refined.silhouette_seconds + work.refined.photo_seconds;
      const double share = batch.size() > 1 && lane_seconds > 0.0 ? (NowSeconds() - refine_start) / lane_seconds : 1.0;
      for (FrameWork& work : batch) {
        const FrameRefinementSummary& refined = work.refined;
        // How far the refinement brought the frames that start from their deformation.
        for (std::size_t i = 0; i < refined.iou_start.size() && !refined.carried; ++i)
          if (!std::isnan(refined.iou_start[i]))
            iou_before += refined.iou_start[i], iou_after += refined.iou_after[i], ++iou_views;
        if (refined.photo.rounds > 0 && !refined.carried)
          flow_before += refined.photo.first_flow_px, flow_after += refined.photo.last_flow_px, ++flow_frames;
        if (refined.carried) ++carried_frames;
        timings->Add("refine_read", work.frame, work.masks_read);
        timings->Add("refine", work.frame, share * refined.silhouette_seconds);
        if (inputs.refine_photo) {
          timings->Add("photo_refine_read", work.frame, work.images_read);
          timings->Add("photo_refine", work.frame, share * refined.photo_seconds);
        }
      }
    }
    for (FrameWork& work : batch) {
      const double write_start = NowSeconds();
      WriteMesh(folder.ScanPath(work.frame), work.animated);
      timings->Add("deform_write", work.frame, NowSeconds() - write_start);
      if (!work.images.empty() && orbit_frames() && !fs::exists(folder.RenderPath(render->view, work.frame)))
        orbit_frames()->Render(work.frame, work.animated.vertices.cast<float>().cast<double>(), work.images, work.masks,
                               timings), ++rendered;
      work.masks.clear();
      work.images.clear();
      if (work.deform.singular) singular_frames.push_back(work.frame);
      previous = work.frame;
      ++report.computed;
      ReportProgress(progress, "deform", ++done, todo.size(), "frame " + std::to_string(work.frame));
    }
  }
  if (iou_views > 0) {
    char line[200];
    std::snprintf(line, sizeof(line), "%s: scan IoU in the used cameras %.4f -> %.4f (mean over %d views%s)",
                  inputs.refine_photo ? "silhouette and photo refinement" : "silhouette refinement", iou_before / iou_views,
                  iou_after / iou_views, iou_views, carried_frames > 0 ? " of the keyframes" : "");
    report.notes.push_back(line);
  }
  if (flow_frames > 0) {
    char line[200];
    std::snprintf(line, sizeof(line),
                  "photo refinement: mean flow between neighbouring cameras through the scan %.3f px -> %.3f px (before "
                  "the last round; mean over %d %s)", flow_before / flow_frames, flow_after / flow_frames, flow_frames,
                  carried_frames > 0 ? "keyframes" : "frames");
    report.notes.push_back(line);
  }
  if (rendered > 0)
    report.notes.push_back(std::to_string(rendered) + " frame(s) of the 3D video drawn as their scans were written (" +
                           folder.Path("renders/" + render->view) + ")");
  if (carried_frames > 0)
    report.notes.push_back(std::to_string(carried_frames) + " frame(s) between keyframes refined from the previous frame's correction");
  if (!singular_frames.empty())
    report.notes.push_back(std::to_string(singular_frames.size()) +
                           " frame(s) near a 180-degree rotation used an intermediate reference (report section 4.3), frames " +
                           std::to_string(singular_frames.front()) + " to " + std::to_string(singular_frames.back()));
  timings->Save();
  report.seconds = NowSeconds() - start;
  return report;
}

}  // namespace confluent
