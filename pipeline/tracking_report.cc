#include "pipeline/tracking_report.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <numeric>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "calib/rig_check.h"
#include "silhouette/overlap.h"
#include "tracking/motion_io.h"

namespace confluent {
namespace fs = std::filesystem;

namespace {

// Ground-truth joints.json of `confluent synth`: joint names and per-frame positions.
struct GroundTruthJoints {
  std::vector<std::string> names;
  std::vector<std::vector<Eigen::Vector3d>> frames;
};

GroundTruthJoints LoadGroundTruthJoints(const std::string& path) {
  GroundTruthJoints gt;
  try {
    const nlohmann::json json = nlohmann::json::parse(ReadTextFile(path));
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

}  // namespace

TrackingReport ReportTracking(const RunInputs& inputs, const BodyTemplate& body, const TrackingReportOptions& options,
                              const ProgressCallback& progress) {
  const Capture& capture = *inputs.capture;
  const Rig& rig = capture.rig();
  const int first = inputs.frames.first, end = inputs.frames.end;
  GroundTruthJoints gt;
  if (!options.gt_joints_path.empty()) gt = LoadGroundTruthJoints(options.gt_joints_path);

  TrackingReport report;
  std::vector<TrackedFrame> results;
  std::vector<double> joint_errors, heldout_ious;
  std::string overlap_csv = "frame,camera,iou,heldout\n";
  for (int frame = first; frame < end; ++frame) {
    PosesFile state = ReadPosesJson(inputs.folder.TrackingStatePath(frame), body, rig.names());
    if (state.frames.size() != 1) throw InputError(inputs.folder.TrackingStatePath(frame), "expected one frame");
    TrackedFrame result = std::move(state.frames[0]);
    const Mesh mesh = ReadMesh(inputs.folder.TemplatePath(frame));
    // Overlap per camera at full resolution, held-out cameras included where their masks exist.
    double heldout_sum = 0;
    int heldout_n = 0;
    for (int c = 0; c < rig.size(); ++c) {
      const std::string path = RunMaskPath(inputs, c, frame);
      if (inputs.cameras.is_held_out(c) && !fs::exists(path)) continue;
      const Image mask = ReadMaskFile(path);
      const Image rendered = RasterizeClosedMesh(mesh, rig.cameras[c]);  // centre-sampled, like GL masks
      const double iou = MaskIoU(rendered, mask);
      const bool held_out = inputs.cameras.is_held_out(c);
      overlap_csv += std::to_string(frame) + "," + rig.cameras[c].name + "," + std::to_string(iou) + "," +
                     (held_out ? "1" : "0") + "\n";
      if (held_out) {
        heldout_ious.push_back(iou);
        heldout_sum += iou;
        ++heldout_n;
      }
      if (options.overlay_every > 0 && ((frame - first) % options.overlay_every == 0 || frame + 1 == end)) {
        const Image overlay = DrawSilhouetteOverlay(capture.ReadFrame(c, frame), rendered, &mask);
        const fs::path dir = fs::path(inputs.folder.Path("overlays")) / rig.cameras[c].name;
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
    report.frame_lines.push_back(line);
    results.push_back(std::move(result));
    ReportProgress(progress, "track report", frame - first + 1, end - first, "frame " + std::to_string(frame));
  }
  WriteTextFile(inputs.folder.Path("overlap.csv"), overlap_csv);
  std::string table = "frame,seconds,cpu_seconds,fit_seconds,iterations\n";
  std::vector<double> frame_seconds, tracked_cpu;
  for (const TrackedFrame& r : results) {
    table += std::to_string(r.frame) + "," + std::to_string(r.seconds) + "," + std::to_string(r.cpu_seconds) + "," +
             std::to_string(r.fit.seconds) + "," + std::to_string(r.fit.iterations) + "\n";
    frame_seconds.push_back(r.seconds);
    if (&r != &results.front()) tracked_cpu.push_back(r.cpu_seconds);
  }
  WriteTextFile(inputs.folder.Path("tracking_frames.csv"), table);

  const std::vector<double> tracked_seconds(frame_seconds.begin() + (frame_seconds.size() > 1 ? 1 : 0), frame_seconds.end());
  double iou_sum = 0;
  int flagged = 0, searched = 0, search_skipped = 0;
  for (const TrackedFrame& r : results) {
    iou_sum += r.mean_iou;
    flagged += std::any_of(r.flags.begin(), r.flags.end(), [](const std::string& f) { return f != "initialized"; });
    searched += r.limb_search == LimbSearch::kRan;
    search_skipped += r.limb_search == LimbSearch::kSkipped;
  }
  nlohmann::json& summary = report.summary;
  const double mean_iou = iou_sum / std::max<std::size_t>(1, results.size());
  summary["frames"] = results.size();
  summary["mean_iou_tracked_cameras"] = mean_iou;
  summary["init_seconds"] = frame_seconds.empty() ? 0.0 : frame_seconds.front();
  summary["median_track_seconds"] = Percentile(tracked_seconds, 0.5);
  summary["median_track_cpu_seconds"] = Percentile(tracked_cpu, 0.5);
  summary["flagged_frames"] = flagged;
  summary["limb_search_frames"] = searched;
  summary["limb_search_skipped_frames"] = search_skipped;
  char line[512];
  std::snprintf(line, sizeof line,
                "tracked %zu frames: mean IoU %.3f (tracked cameras), init %.2fs, median %.3fs per frame (cpu %.3fs), %d flagged",
                results.size(), mean_iou, frame_seconds.empty() ? 0.0 : frame_seconds.front(),
                Percentile(tracked_seconds, 0.5), Percentile(tracked_cpu, 0.5), flagged);
  report.summary_lines.push_back(line);
  if (searched + search_skipped > 0) {
    std::snprintf(line, sizeof line,
                  "lost-limb search: ran on %d frame(s), skipped on %d no worse than a fruitless search before", searched,
                  search_skipped);
    report.summary_lines.push_back(line);
  }
  if (!heldout_ious.empty()) {
    const double mean = std::accumulate(heldout_ious.begin(), heldout_ious.end(), 0.0) / heldout_ious.size();
    const double minimum = *std::min_element(heldout_ious.begin(), heldout_ious.end());
    summary["heldout_iou_mean"] = mean;
    summary["heldout_iou_min"] = minimum;
    std::snprintf(line, sizeof line, "held-out IoU: mean %.4f, min %.4f over %zu camera-frames", mean, minimum,
                  heldout_ious.size());
    report.summary_lines.push_back(line);
  }
  if (!joint_errors.empty()) {
    const double mean = std::accumulate(joint_errors.begin(), joint_errors.end(), 0.0) / joint_errors.size();
    summary["joint_error_mean_m"] = mean;
    summary["joint_error_p95_m"] = Percentile(joint_errors, 0.95);
    summary["joint_error_max_m"] = Percentile(joint_errors, 1.0);
    std::snprintf(line, sizeof line, "joint error: mean %.2f cm, 95th percentile %.2f cm, max %.2f cm (%zu joint-frames)",
                  mean * 100, Percentile(joint_errors, 0.95) * 100, Percentile(joint_errors, 1.0) * 100,
                  joint_errors.size());
    report.summary_lines.push_back(line);
  }
  WriteTextFile(inputs.folder.Path("track_summary.json"), summary.dump(1) + "\n");
  return report;
}

}  // namespace confluent
