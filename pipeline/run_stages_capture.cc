// The capture-side stages of `confluent run`: silhouettes and tracking.

#include <cstdio>
#include <algorithm>
#include <filesystem>
#include <map>
#include <mutex>

#include "pipeline/run_stages.h"
#include "pipeline/mask_confidence.h"
#include "core/bvh_io.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "silhouette/silhouette.h"
#include "tracking/motion_io.h"
#include "pipeline/frame_landmarks.h"
#include "tracking/tracker.h"

namespace confluent {
namespace fs = std::filesystem;

std::string RunMaskPath(const RunInputs& inputs, int camera, int frame) {
  const std::string& name = inputs.capture->rig().cameras[camera].name;
  if (!inputs.masks_dir.empty()) return (fs::path(inputs.masks_dir) / name / (FrameStem(frame) + ".png")).string();
  return inputs.folder.MaskPath(name, frame);
}

std::vector<Image> TrackingMasks(const RunInputs& inputs, int frame) {
  const Rig& rig = inputs.capture->rig();
  std::vector<Image> masks(rig.size());
  for (int c = 0; c < rig.size(); ++c) {
    if (inputs.cameras.is_held_out(c)) continue;
    const std::string path = RunMaskPath(inputs, c, frame);
    masks[c] = ReadMaskFile(path);
    if (masks[c].width != rig.cameras[c].width || masks[c].height != rig.cameras[c].height)
      throw InputError(path, "mask size differs from the calibration of camera " + rig.cameras[c].name);
  }
  return masks;
}

namespace {

// The masks the tracker will read, checked against each other through the calibration on a
// sample of frames (silhouette/multiview.h).
MaskTrust AssessRunMasks(const RunInputs& inputs) {
  std::vector<int> frames;
  for (int k : EvenFrameSample(inputs.frames.size(), 12)) frames.push_back(inputs.frames.first + k);
  return AssessMaskTrust(
      inputs.capture->rig(), frames,
      [&](int camera, int frame) {
        const std::string path = RunMaskPath(inputs, camera, frame);
        return inputs.cameras.is_used(camera) && fs::exists(path) ? ReadMaskFile(path) : Image();
      },
      MultiViewOptions{});
}

// RUN/mask_confidence.json: the masks on disk assessed on a sample of frames, written when the
// stage made masks or the record is missing (so a resumed run writes what an uninterrupted one
// does, and a finished run rewrites nothing). Says before tracking starts what it holds: when the
// masks cannot be trusted, the stage's first note (`known_warning`, from checking every
// camera-frame as it was made, takes precedence); the low-confidence camera-frames, a later one.
void RecordMaskTrust(const RunInputs& inputs, bool masks_made, const std::string& known_warning, StageReport* report) {
  const std::string path = inputs.folder.Path("mask_confidence.json");
  MaskConfidenceRecord record;
  if (masks_made || !fs::exists(path)) {
    record = MakeMaskConfidenceRecord(inputs.capture->rig(), AssessRunMasks(inputs), MultiViewOptions().min_confidence,
                                      "sample");
    WriteMaskConfidence(path, record);
  } else {
    record = ReadMaskConfidence(path);
  }
  const std::string& warning = known_warning.empty() ? record.warning : known_warning;
  if (!warning.empty()) report->notes.insert(report->notes.begin(), "warning: " + warning);
  if (!record.low_frames.empty()) {
    char head[160];
    std::snprintf(head, sizeof head, "%zu of %d sampled camera-frames below confidence %.2f: ", record.low_frames.size(),
                  record.camera_frames, record.min_confidence);
    report->notes.push_back(head + LowConfidenceList(record) + " (" + path + ")");
  }
}

}  // namespace

StageReport RunSilhouetteStage(const RunInputs& inputs, const ProgressCallback& progress, TimingLog* timings) {
  StageReport report("silhouettes");
  const double start = NowSeconds();
  const Capture& capture = *inputs.capture;
  if (!inputs.masks_dir.empty()) {
    for (int c = 0; c < capture.num_cameras(); ++c)
      if (inputs.cameras.is_used(c) && !fs::exists(RunMaskPath(inputs, c, inputs.frames.first)))
        throw InputError(RunMaskPath(inputs, c, inputs.frames.first), "mask file not found (given --masks folder)");
    report.skipped = inputs.frames.size();
    report.notes.push_back("masks given: " + inputs.masks_dir);
    RecordMaskTrust(inputs, false, "", &report);
    return report;
  }
  // Per camera, the first frame whose mask is missing: a resumed run continues each camera there.
  // The extractor is still prepared at the range's first frame (its background refinement uses
  // the frames from there), so a resumed run writes the masks an uninterrupted one would.
  const int num_cameras = capture.num_cameras();
  std::vector<int> first_missing(num_cameras, inputs.frames.end);
  int frames_done = inputs.frames.end;  // frames with every camera's mask
  for (int c = 0; c < num_cameras; ++c) {
    for (int frame = inputs.frames.first; frame < inputs.frames.end; ++frame)
      if (!fs::exists(RunMaskPath(inputs, c, frame))) {
        first_missing[c] = frame;
        break;
      }
    frames_done = std::min(frames_done, first_missing[c]);
  }
  report.skipped = frames_done - inputs.frames.first;
  if (frames_done == inputs.frames.end) {
    RecordMaskTrust(inputs, false, "", &report);
    return report;
  }

  SilhouetteOptions options;
  options.threads = inputs.threads;
  options.multiview_exclude = inputs.cameras.held_out_mask();  // held-out images must not shape the used masks
  std::mutex mutex;
  std::map<int, int> cameras_done;
  for (int frame = frames_done; frame < inputs.frames.end; ++frame)
    for (int c = 0; c < num_cameras; ++c) cameras_done[frame] += first_missing[c] > frame;
  double last_frame_done = NowSeconds();
  auto sink = [&](int camera, int frame, const Image&, const Image& mask, const MaskSummary& summary) {
    WriteImage(RunMaskPath(inputs, camera, frame), mask);
    std::lock_guard<std::mutex> lock(mutex);
    if (summary.empty) report.notes.push_back("empty mask: " + capture.rig().cameras[camera].name + " frame " + std::to_string(frame));
    if (++cameras_done[frame] == num_cameras) {
      const double now = NowSeconds();
      timings->Add("silhouettes", frame, now - last_frame_done);
      last_frame_done = now;
    }
  };
  const SilhouetteSummary summary =
      ExtractSilhouettes(capture, inputs.frames.first, inputs.frames.end, options, sink, progress, first_missing);
  for (const std::string& warning : summary.warnings)
    if (warning != summary.trust.warning) report.notes.push_back(warning);  // said first, below
  report.computed = inputs.frames.end - frames_done;
  report.seconds = NowSeconds() - start;
  timings->Save();
  RecordMaskTrust(inputs, true, summary.trust.warning, &report);
  return report;
}

namespace {

bool TrackedFrameFinished(const RunFolder& folder, int frame) {
  return fs::exists(folder.TrackingStatePath(frame)) && fs::exists(folder.TemplatePath(frame));
}

}  // namespace

StageReport RunTrackingStage(const RunInputs& inputs, const BodyTemplate& body, const ProgressCallback& progress,
                             TimingLog* timings, BodyShape* shape) {
  StageReport report("tracking");
  const double start = NowSeconds();
  const Rig& rig = inputs.capture->rig();
  const std::vector<std::string> camera_names = rig.names();
  fs::create_directories(inputs.folder.Path("tracking"));
  fs::create_directories(inputs.folder.Path("template"));
  Tracker tracker(rig, inputs.cameras.held_out_mask(), inputs.tracker);
  std::vector<bool> tracking_cameras = inputs.cameras.held_out_mask();
  tracking_cameras.flip();
  FrameLandmarks landmarks(*inputs.capture, tracking_cameras);
  if (inputs.landmarks) tracker.UseLandmarks([&landmarks](int frame) { return landmarks.Joints(frame); });
  // The shape is learned over the first frames whose masks are there (a first shard's own).
  tracker.UseLaterMasks([&inputs](int frame) {
    const Rig& rig = inputs.capture->rig();
    for (int c = 0; c < rig.size(); ++c)
      if (!inputs.cameras.is_held_out(c) && (frame >= inputs.capture->num_frames() || !fs::exists(RunMaskPath(inputs, c, frame))))
        return std::vector<Image>();
    return TrackingMasks(inputs, frame);
  });
  auto read_state = [&](int frame) {
    PosesFile state = ReadPosesJson(inputs.folder.TrackingStatePath(frame), body, camera_names);
    if (state.frames.size() != 1) throw InputError(inputs.folder.TrackingStatePath(frame), "expected one frame");
    return state;
  };
  // Progress (rate and ETA) counts only the frames to compute, as in the other stages.
  std::size_t todo = 0, done = 0;
  for (int frame = inputs.frames.first; frame < inputs.frames.end; ++frame) todo += !TrackedFrameFinished(inputs.folder, frame);
  for (int frame = inputs.frames.first; frame < inputs.frames.end; ++frame) {
    if (TrackedFrameFinished(inputs.folder, frame)) {
      ++report.skipped;
      continue;
    }
    if (!tracker.initialized() && frame > 0 && TrackedFrameFinished(inputs.folder, frame - 1)) {
      // Continue from the saved state of the frames just before (a resumed run or a shard
      // boundary): as far back as the tracker's windows reach past repeated frames.
      std::vector<TrackedFrame> before;
      BodyShape saved_shape;
      int kept = 0;
      for (int back = frame - 1; back >= 0 && kept < Tracker::kIouWindow; --back) {
        if (!TrackedFrameFinished(inputs.folder, back)) continue;
        PosesFile state = read_state(back);
        if (before.empty()) saved_shape = state.shape;
        kept += !IsRepeatedFrame(state.frames[0]);
        before.push_back(std::move(state.frames[0]));
      }
      std::reverse(before.begin(), before.end());  // oldest first
      tracker.ResumeAfter(saved_shape, before, TrackingMasks(inputs, frame - 1));
    }
    const std::vector<Image> masks = TrackingMasks(inputs, frame);
    const double frame_start = NowSeconds();
    TrackedFrame result = tracker.initialized() ? tracker.Track(frame, masks) : tracker.Initialize(frame, masks);
    if (!tracker.initialized())
      throw InputError(RunMaskPath(inputs, 0, frame), "frame " + std::to_string(frame) +
                                                          ": no visual hull from the masks (empty or inconsistent masks)");
    WriteMesh(inputs.folder.TemplatePath(frame), body.PosedMesh(tracker.shape(), result.pose));
    WritePosesJson(inputs.folder.TrackingStatePath(frame), body, tracker.shape(), camera_names, {result}, inputs.fps);
    timings->Add("tracking", frame, NowSeconds() - frame_start);
    for (const std::string& flag : result.flags)
      if (flag != "initialized") report.notes.push_back("frame " + std::to_string(frame) + ": " + flag);
    ++report.computed;
    ReportProgress(progress, "tracking", ++done, todo,
                   "frame " + std::to_string(frame) + " IoU " + std::to_string(result.mean_iou).substr(0, 5));
    if (report.computed % 10 == 0) timings->Save();
  }
  timings->Save();
  report.notes.insert(report.notes.end(), landmarks.notes().begin(), landmarks.notes().end());

  // poses.json and motion.bvh over every frame tracked so far (all shards).
  std::vector<TrackedFrame> frames;
  for (int frame = 0; frame < inputs.capture->num_frames(); ++frame) {
    if (!TrackedFrameFinished(inputs.folder, frame)) continue;
    PosesFile state = read_state(frame);
    if (frame == inputs.frames.first || frames.empty()) *shape = state.shape;
    frames.push_back(std::move(state.frames[0]));
  }
  WritePosesJson(inputs.folder.Path("poses.json"), body, *shape, camera_names, frames, inputs.fps);
  std::vector<Pose> poses;
  for (const TrackedFrame& f : frames) poses.push_back(body.ToPose(f.pose));
  WriteBvh(inputs.folder.Path("motion.bvh"), body.MakeSkeleton(*shape), poses, 1.0 / inputs.fps);
  double iou_sum = 0;
  for (const TrackedFrame& f : frames) iou_sum += f.mean_iou;
  report.notes.push_back("mean IoU on the tracking cameras " + std::to_string(iou_sum / std::max<std::size_t>(1, frames.size())).substr(0, 5) +
                         " over " + std::to_string(frames.size()) + " frames");
  report.seconds = NowSeconds() - start;
  return report;
}

}  // namespace confluent
