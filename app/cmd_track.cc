// confluent track CAPTURE [--exclude-camera NAME]... [--masks DIR] --out RUN: marker-less motion
// capture with the 16-segment body template.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numeric>

#include "app/commands.h"
#include "pipeline/camera_selection.h"
#include "pipeline/frame_range.h"
#include "pipeline/run_manifest.h"
#include "calib/capture.h"
#include "calib/rig_check.h"
#include "core/atomic_file.h"
#include "core/bvh_io.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "silhouette/overlap.h"
#include "tracking/motion_io.h"
#include "tracking/tracker.h"

namespace confluent::app {
namespace fs = std::filesystem;

namespace {

// Ground-truth joints.json of `confluent synth`: joint names and per-frame positions.
struct GroundTruthJoints {
  std::vector<std::string> names;
  std::vector<std::vector<Eigen::Vector3d>> frames;
};

GroundTruthJoints LoadGroundTruthJoints(const std::string& path) {
  GroundTruthJoints gt;
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(ReadTextFile(path));
    gt.names = json.at("joint_names").get<std::vector<std::string>>();
    for (const auto& frame : json.at("frames")) {
      std::vector<Eigen::Vector3d> positions;
      for (const auto& p : frame.at("positions")) positions.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
      gt.frames.push_back(positions);
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, std::string("not a joints.json: ") + e.what());
  }
  return gt;
}

// The articulation joints used by the joint-error metric (end sites excluded).
bool IsMetricJoint(const std::string& name) {
  return name.size() < 4 || (name.substr(name.size() - 4) != "_end" && name.substr(name.size() - 3) != "toe");
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * (v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(pos);
  const double t = pos - i;
  return i + 1 < v.size() ? v[i] * (1 - t) + v[i + 1] * t : v[i];
}

int RunTrack(const ParsedArgs& args, const Context& context) {
  const std::string root = args.positionals()[0];
  const std::string out_dir = args.get("out");
  CaptureOptions capture_options;
  capture_options.check_every_image_header = false;
  const Capture capture = Capture::Open(root, capture_options);
  const Rig& rig = capture.rig();
  const CameraSelection cameras(rig, args.get_all("exclude-camera"));
  const std::vector<bool>& excluded = cameras.held_out_mask();
  const std::string masks_dir = args.get("masks", (fs::path(root) / "masks").string());
  if (!fs::is_directory(masks_dir))
    throw InputError(masks_dir, "no masks folder (run `confluent silhouettes` first, or pass --masks DIR)");
  const FrameRange range = ParseFrameRange(args.get("frames"), capture.num_frames());
  const int first = range.first, end = range.end;
  const int overlay_every = args.get_int("overlay-every", 25);
  TrackerOptions options;
  options.fit.downscale = args.get_int("downscale", options.fit.downscale);
  options.fit.num_threads = args.get_int("threads", options.fit.num_threads);
  options.Check();
  GroundTruthJoints gt;
  if (args.has("gt-joints")) gt = LoadGroundTruthJoints(args.get("gt-joints"));

  fs::create_directories(fs::path(out_dir) / "template");
  auto mask_path = [&](int camera, int frame) {
    return (fs::path(masks_dir) / rig.cameras[camera].name / (FrameStem(frame) + ".png")).string();
  };
  Tracker tracker(rig, excluded, options);
  const BodyTemplate& body = tracker.body();
  std::vector<TrackedFrame> results;
  std::vector<Pose> poses;
  std::vector<double> joint_errors, heldout_ious;
  std::vector<double> frame_seconds;
  std::string overlap_csv = "frame,camera,iou,heldout\n";
  const ProgressCallback progress = context.make_progress();
  std::vector<std::string> report_lines;
  for (int frame = first; frame < end; ++frame) {
    std::vector<Image> masks(rig.size());
    for (int c = 0; c < rig.size(); ++c) {
      const std::string path = mask_path(c, frame);
      if (excluded[c]) {
        if (fs::exists(path)) masks[c] = ReadMaskFile(path);  // for the held-out overlap only
        continue;
      }
      masks[c] = ReadMaskFile(path);
      if (masks[c].width != rig.cameras[c].width || masks[c].height != rig.cameras[c].height)
        throw InputError(path, "mask size differs from the calibration of camera " + rig.cameras[c].name);
    }
    std::vector<Image> tracking_masks = masks;
    for (int c = 0; c < rig.size(); ++c)
      if (excluded[c]) tracking_masks[c] = Image();
    TrackedFrame result = tracker.initialized() ? tracker.Track(frame, tracking_masks) : tracker.Initialize(frame, tracking_masks);
    if (!tracker.initialized()) throw InputError(masks_dir, "frame " + std::to_string(frame) + ": no visual hull (empty or inconsistent masks)");
    frame_seconds.push_back(result.seconds);
    // Overlap per camera at full resolution, held-out cameras included.
    const Mesh mesh = body.PosedMesh(tracker.shape(), result.pose);
    WriteMesh((fs::path(out_dir) / "template" / (FrameStem(frame) + ".ply")).string(), mesh);
    double heldout_sum = 0;
    int heldout_n = 0;
    for (int c = 0; c < rig.size(); ++c) {
      if (masks[c].empty()) continue;
      const Image rendered = RasterizeClosedMesh(mesh, rig.cameras[c]);  // centre-sampled, like GL masks
      const double iou = MaskIoU(rendered, masks[c]);
      overlap_csv += std::to_string(frame) + "," + rig.cameras[c].name + "," + std::to_string(iou) + "," +
                     (excluded[c] ? "1" : "0") + "\n";
      if (excluded[c]) {
        heldout_ious.push_back(iou);
        heldout_sum += iou;
        ++heldout_n;
      }
      if (overlay_every > 0 && ((frame - first) % overlay_every == 0 || frame + 1 == end)) {
        const Image overlay = DrawSilhouetteOverlay(capture.ReadFrame(c, frame), rendered, &masks[c]);
        const fs::path dir = fs::path(out_dir) / "overlays" / rig.cameras[c].name;
        fs::create_directories(dir);
        WriteImage((dir / (FrameStem(frame) + ".png")).string(), overlay);
      }
    }
    double frame_joint_error = -1;
    if (!gt.frames.empty() && frame < static_cast<int>(gt.frames.size())) {
      double sum = 0;
      int n = 0;
      for (std::size_t j = 0; j < gt.names.size(); ++j) {
        const auto it = std::find(body.joint_names().begin(), body.joint_names().end(), gt.names[j]);
        if (it == body.joint_names().end() || !IsMetricJoint(gt.names[j])) continue;
        const double e = (result.joints[it - body.joint_names().begin()] - gt.frames[frame][j]).norm();
        joint_errors.push_back(e);
        sum += e;
        ++n;
      }
      frame_joint_error = n ? sum / n : -1;
    }
    std::string flags;
    for (const std::string& f : result.flags) flags += (flags.empty() ? "" : ",") + f;
    char line[512];
    std::snprintf(line, sizeof line, "frame %06d  iou %.3f  heldout %s  outside %.2fpx  contour %.2fpx  iters %3d  %.2fs (cpu %.2fs)%s%s%s",
                  frame, result.mean_iou, heldout_n ? std::to_string(heldout_sum / heldout_n).substr(0, 5).c_str() : "  -  ",
                  result.fit.mean_outside_px, result.fit.mean_contour_px, result.fit.iterations, result.seconds, result.cpu_seconds,
                  frame_joint_error >= 0 ? ("  joints " + std::to_string(frame_joint_error * 100).substr(0, 5) + "cm").c_str() : "",
                  flags.empty() ? "" : "  ", flags.c_str());
    report_lines.push_back(line);
    poses.push_back(body.ToPose(result.pose));
    results.push_back(std::move(result));
    ReportProgress(progress, "track", frame - first + 1, end - first, "frame " + std::to_string(frame));
  }
  const double fps = RunFrameRate(capture);
  WritePosesJson((fs::path(out_dir) / "poses.json").string(), body, tracker.shape(), rig.names(), results, fps);
  WriteBvh((fs::path(out_dir) / "motion.bvh").string(), body.MakeSkeleton(tracker.shape()), poses, 1.0 / fps);
  WriteTextFile((fs::path(out_dir) / "overlap.csv").string(), overlap_csv);
  std::string timings = "frame,seconds,cpu_seconds,fit_seconds,iterations\n";
  std::vector<double> tracked_cpu;
  for (const TrackedFrame& r : results) {
    timings += std::to_string(r.frame) + "," + std::to_string(r.seconds) + "," + std::to_string(r.cpu_seconds) + "," +
               std::to_string(r.fit.seconds) + "," + std::to_string(r.fit.iterations) + "\n";
    if (&r != &results.front()) tracked_cpu.push_back(r.cpu_seconds);
  }
  WriteTextFile((fs::path(out_dir) / "timings.csv").string(), timings);

  for (const std::string& line : report_lines) std::printf("%s\n", line.c_str());
  std::vector<double> tracked_seconds(frame_seconds.begin() + (frame_seconds.size() > 1 ? 1 : 0), frame_seconds.end());
  double iou_sum = 0;
  int flagged = 0;
  for (const TrackedFrame& r : results) {
    iou_sum += r.mean_iou;
    for (const std::string& f : r.flags)
      if (f != "initialized") {
        ++flagged;
        break;
      }
  }
  nlohmann::json summary;
  summary["frames"] = results.size();
  summary["mean_iou_tracked_cameras"] = iou_sum / std::max<std::size_t>(1, results.size());
  summary["init_seconds"] = frame_seconds.empty() ? 0.0 : frame_seconds.front();
  summary["median_track_seconds"] = Percentile(tracked_seconds, 0.5);
  summary["median_track_cpu_seconds"] = Percentile(tracked_cpu, 0.5);
  summary["flagged_frames"] = flagged;
  std::printf("tracked %zu frames: mean IoU %.3f (tracked cameras), init %.2fs, median %.3fs per frame (cpu %.3fs), %d flagged\n",
              results.size(), iou_sum / std::max<std::size_t>(1, results.size()),
              frame_seconds.empty() ? 0.0 : frame_seconds.front(), Percentile(tracked_seconds, 0.5),
              Percentile(tracked_cpu, 0.5), flagged);
  if (!heldout_ious.empty()) {
    const double mean = std::accumulate(heldout_ious.begin(), heldout_ious.end(), 0.0) / heldout_ious.size();
    summary["heldout_iou_mean"] = mean;
    summary["heldout_iou_min"] = *std::min_element(heldout_ious.begin(), heldout_ious.end());
    std::printf("held-out IoU: mean %.4f, min %.4f over %zu camera-frames\n", mean,
                *std::min_element(heldout_ious.begin(), heldout_ious.end()), heldout_ious.size());
  }
  if (!joint_errors.empty()) {
    const double mean = std::accumulate(joint_errors.begin(), joint_errors.end(), 0.0) / joint_errors.size();
    summary["joint_error_mean_m"] = mean;
    summary["joint_error_p95_m"] = Percentile(joint_errors, 0.95);
    summary["joint_error_max_m"] = Percentile(joint_errors, 1.0);
    std::printf("joint error: mean %.2f cm, 95th percentile %.2f cm, max %.2f cm (%zu joint-frames)\n", mean * 100,
                Percentile(joint_errors, 0.95) * 100, Percentile(joint_errors, 1.0) * 100, joint_errors.size());
  }
  WriteTextFile((fs::path(out_dir) / "track_summary.json").string(), summary.dump(1) + "\n");
  std::printf("poses in %s, motion in %s, meshes in %s\n", (fs::path(out_dir) / "poses.json").string().c_str(),
              (fs::path(out_dir) / "motion.bvh").string().c_str(), (fs::path(out_dir) / "template").string().c_str());
  return 0;
}

}  // namespace

CommandSpec MakeTrackCommand() {
  CommandSpec spec;
  spec.name = "track";
  spec.summary = "marker-less motion capture: fit the 16-segment body template to the silhouettes";
  spec.usage = "CAPTURE [--exclude-camera NAME]... [--masks DIR] --out RUN";
  spec.description =
      "Initialises the body template automatically on the first frame (placement from the visual hull, then a\n"
      "joint shape-and-pose fit) and tracks it frame by frame with Ceres (silhouette distance transforms,\n"
      "contour rays, constant-velocity prediction, bad-frame recovery). Reads CAPTURE/masks/<cam>/<frame>.png\n"
      "(or --masks DIR). Excluded (held-out) cameras are not used; when their masks exist, their overlap is\n"
      "reported. Writes RUN/poses.json, RUN/motion.bvh (Y-up, cm), RUN/template/<frame>.ply (face label =\n"
      "segment), RUN/overlap.csv (IoU per frame and camera), RUN/overlays/<cam>/<frame>.png (template contour red,\n"
      "mask green), RUN/timings.csv and RUN/track_summary.json, and prints a per-frame summary.";
  spec.min_positionals = spec.max_positionals = 1;
  spec.options = {
      {"out", "RUN", "output folder", false, true},
      {"exclude-camera", "NAME", "do not use this camera (held out)", true},
      {"masks", "DIR", "masks folder DIR/<cam>/<frame>.png (default CAPTURE/masks)"},
      {"frames", "A:B", "frame range, B exclusive (default: all frames)"},
      {"gt-joints", "FILE", "ground-truth joints.json of `confluent synth`: report the 3D joint error"},
      {"overlay-every", "N", "write overlays every N frames (default 25; 0 = none)"},
      {"downscale", "N", "mask reduction for fitting (default 0 = automatic, about 256 px across)"},
      {"threads", "N", "solver threads (default 2)"},
  };
  spec.run = RunTrack;
  return spec;
}

}  // namespace confluent::app
