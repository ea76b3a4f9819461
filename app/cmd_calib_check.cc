// confluent calib check CAPTURE: plausibility report, overlays and visual-hull consistency.

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "calib/capture.h"
#include "calib/easymocap_io.h"
#include "calib/rig_check.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "silhouette/multiview.h"

namespace confluent::app {
namespace fs = std::filesystem;

namespace {

// The silhouettes' multi-view confidence of the same masks (silhouette/multiview.h), beside the hull
// IoU: with few cameras even true masks score a low IoU (a hull from three is much larger than the
// person), whereas the part of a mask the others' hull explains stays near 1 for good masks.
void PrintMaskConfidence(const Rig& rig, std::vector<Image> masks, nlohmann::json* json) {
  const std::vector<ViewConsistency> views = CheckMultiView(rig, &masks, {}, MultiViewOptions());
  std::printf("\nmulti-view confidence (as `silhouettes` scores masks; hull of every camera %.2f m3):\n",
              views.empty() ? 0.0 : views[0].hull_volume_m3);
  for (int c = 0; c < rig.size(); ++c) {
    const ViewConsistency& view = views[c];
    std::printf("  %-12s explained %.3f  covered %.3f  confidence %.3f\n", rig.cameras[c].name.c_str(),
                view.explained, view.covered, view.confidence);
    (*json)["mask_confidence"][rig.cameras[c].name] = {
        {"explained", view.explained}, {"covered", view.covered}, {"confidence", view.confidence}};
  }
}

int RunCalibCheck(const ParsedArgs& args, const Context& context) {
  const std::string root = args.positionals()[0];
  const std::string out_dir = args.get("out", (fs::path(root) / "check").string());
  const int frame = args.get_int("frame", 0);
  const double min_iou = args.get_double("min-iou", 0.8);

  // A calibration-only folder is allowed: then there are no overlays on images or hull checks.
  const bool has_frames = fs::is_directory(fs::path(root) / "images") || fs::is_directory(fs::path(root) / "videos");
  std::unique_ptr<Capture> capture;
  Rig rig;
  if (has_frames) {
    capture = std::make_unique<Capture>(Capture::Open(root));
    rig = capture->rig();
    if (frame < 0 || frame >= capture->num_frames())
      throw UsageError("--frame " + std::to_string(frame) + " is out of range (0.." +
                       std::to_string(capture->num_frames() - 1) + ")");
  } else {
    rig = ReadEasyMocap((fs::path(root) / "intri.yml").string(), (fs::path(root) / "extri.yml").string());
  }

  const RigCheckReport report = CheckRig(rig);
  std::printf("%s", report.ToString().c_str());
  nlohmann::json json;
  json["volume_center_m"] = {report.volume_center.x(), report.volume_center.y(), report.volume_center.z()};
  json["extent_m"] = report.extent_m;
  json["warnings"] = report.warnings;

  // Overlays: world axes and a 1 m ground grid on the chosen frame (or a grey image).
  ProgressCallback progress = context.make_progress();
  for (int c = 0; c < rig.size(); ++c) {
    const Camera& camera = rig.cameras[c];
    Image base = capture ? capture->ReadFrame(c, frame) : Image(camera.width, camera.height, 3);
    if (!capture) std::fill(base.data.begin(), base.data.end(), 64);
    WriteImage((fs::path(out_dir) / (camera.name + ".png")).string(), DrawWorldOverlay(camera, base));
    ReportProgress(progress, "overlays", c + 1, rig.size(), camera.name);
  }

  bool hull_ok = true;
  if (capture && capture->has_masks()) {
    std::vector<Image> masks;
    for (int c = 0; c < rig.size(); ++c) masks.push_back(capture->ReadMask(c, frame));
    std::vector<int> targets;
    for (const auto& name : args.get_all("heldout")) {
      const int index = rig.IndexOf(name);
      if (index < 0) throw UsageError("--heldout " + name + ": no such camera");
      targets.push_back(index);
    }
    VisualHullOptions hull_options;
    hull_options.grid_resolution = args.get_int("hull-resolution", 160);
    std::vector<Image> hulls;
    const std::vector<double> ious = VisualHullConsistency(rig, masks, targets, hull_options, &hulls);
    std::printf("\nvisual-hull consistency (frame %d; hull from %s, projected into):\n", frame,
                targets.empty() ? "all other cameras" : "the non-held-out cameras");
    double sum = 0;
    for (std::size_t i = 0; i < ious.size(); ++i) {
      const int c = targets.empty() ? static_cast<int>(i) : targets[i];
      std::printf("  %-12s IoU %.3f%s\n", rig.cameras[c].name.c_str(), ious[i], ious[i] < min_iou ? "  LOW" : "");
      json["hull_iou"][rig.cameras[c].name] = ious[i];
      hull_ok = hull_ok && ious[i] >= min_iou;
      sum += ious[i];
      WriteImage((fs::path(out_dir) / (rig.cameras[c].name + "_hull.png")).string(), hulls[i]);
    }
    std::printf("  mean IoU %.3f\n", sum / std::max<std::size_t>(1, ious.size()));
    if (targets.empty()) PrintMaskConfidence(rig, masks, &json);
  }
  WriteTextFile((fs::path(out_dir) / "check.json").string(), json.dump(2));
  std::printf("\noverlays written to %s\n", out_dir.c_str());
  if (!report.warnings.empty() || !hull_ok) {
    std::fprintf(stderr, "confluent calib check: %s: %zu warning(s)%s\n", root.c_str(), report.warnings.size(),
                 hull_ok ? "" : ", visual hull inconsistent with the masks");
    return 1;
  }
  std::printf("calibration looks consistent\n");
  return 0;
}

}  // namespace

CommandSpec MakeCalibCheckCommand() {
  CommandSpec spec;
  spec.name = "calib check";
  spec.summary = "check a capture's calibration: geometry, units, overlays, visual-hull consistency";
  spec.usage = "CAPTURE [--out DIR] [--frame N] [--heldout NAME]...";
  spec.description =
      "Reports per camera the distance to the capture volume, whether it looks at it, focal length and field of\n"
      "view, and baselines; warns on implausible units, mixed handedness and cameras facing away. Writes\n"
      "DIR/<cam>.png with the world axes (X red, Y green, Z blue) and a 1 m ground grid. When the capture has\n"
      "masks/, carves a visual hull from the other cameras and reports its IoU with each camera's mask, and\n"
      "(without --heldout) each mask's multi-view confidence as `silhouettes` computes it: the part of the\n"
      "mask the others' hull explains and the part of that hull it covers.\n"
      "Exit status 1 when a warning is raised or a hull IoU is below --min-iou.";
  spec.min_positionals = spec.max_positionals = 1;
  spec.options = {
      {"out", "DIR", "where overlays and check.json go (default CAPTURE/check)"},
      {"frame", "N", "frame used for overlays and masks (default 0)"},
      {"heldout", "NAME", "hull from the other cameras, scored in this one", true},
      {"min-iou", "X", "hull IoU below this fails the check (default 0.8)"},
      {"hull-resolution", "N", "voxels along the hull box's longest side (default 160)"},
  };
  spec.run = RunCalibCheck;
  return spec;
}

}  // namespace confluent::app
