#include "pipeline/silhouette_folder.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "silhouette/overlay.h"

namespace confluent {
namespace fs = std::filesystem;

namespace {

std::string FrameName(int frame) { return FrameStem(frame) + ".png"; }

nlohmann::json SummaryJson(const Capture& capture, const SilhouetteSummary& summary, int first, int end) {
  nlohmann::json json;
  json["capture"] = capture.root();
  json["frames"] = {first, end};
  json["warnings"] = summary.warnings;
  json["num_flagged"] = summary.num_flagged();
  // Multi-view confidence (silhouette/multiview.h): how far the masks can be trusted.
  json["num_low_confidence"] = summary.trust.low_confidence;
  json["mean_confidence"] = summary.trust.mean_confidence;
  json["trusted"] = summary.trust.warning.empty();
  for (std::size_t index = 0; index < summary.cameras.size(); ++index) {
    const CameraSilhouetteInfo& info = summary.cameras[index];
    nlohmann::json camera;
    camera["name"] = info.name;
    camera["method"] = SilhouetteMethodName(info.method);
    camera["plate"] = info.plate_path;
    camera["noise_sigma"] = info.noise_sigma;
    camera["threshold_scale"] = info.threshold_scale;
    camera["greenness"] = info.greenness;
    camera["warnings"] = info.warnings;
    camera["mean_confidence"] =
        index < summary.trust.camera_confidence.size() ? summary.trust.camera_confidence[index] : 1.0;
    json["cameras"].push_back(camera);
  }
  for (const MaskSummary& mask : summary.masks) {
    json["masks"].push_back({{"camera", capture.rig().cameras[mask.camera].name},
                             {"frame", mask.frame},
                             {"foreground_fraction", mask.foreground_fraction},
                             {"parts", mask.parts},
                             {"empty", mask.empty},
                             {"full", mask.full},
                             {"touches_border", mask.touches_border},
                             {"area_jump", mask.area_jump},
                             {"fragmented", mask.fragmented},
                             {"hull_explained", mask.hull_explained},
                             {"hull_volume_m3", mask.hull_volume_m3},
                             {"hull_covered", mask.hull_covered},
                             {"corrected_pixels", mask.corrected_pixels},
                             {"confidence", mask.confidence},
                             {"low_confidence", mask.low_confidence}});
  }
  return json;
}

}  // namespace

SilhouetteFolderSummary ExtractSilhouettesToFolder(const Capture& capture, const FrameRange& range,
                                                   const std::string& out_dir, const SilhouetteFolderOptions& options,
                                                   const ProgressCallback& progress) {
  options.silhouettes.Check();
  RequireOption(options.overlay_width >= 32 && options.overlay_width <= 4096, "SilhouetteFolderOptions.overlay_width",
                options.overlay_width, "within [32, 4096]");
  SilhouetteFolderSummary result;
  const int first = range.first, end = range.end;
  // Contact sheets: tiles wait here until every camera of their frame is done.
  std::mutex mutex;
  std::map<int, std::vector<Image>> pending;
  const int num_cameras = capture.num_cameras();
  const std::string overlay_dir = (fs::path(out_dir) / "overlays").string();
  // Optional comparison with reference masks: IoU per camera and frame (-1 = no reference).
  const std::string& compare_dir = options.compare_dir;
  std::vector<double> ious(static_cast<std::size_t>(num_cameras) * (end - first), -1.0);
  auto sink = [&](int camera, int frame, const Image& image, const Image& mask, const MaskSummary& summary) {
    const std::string& name = capture.rig().cameras[camera].name;
    WriteImage((fs::path(out_dir) / name / FrameName(frame)).string(), mask);
    if (!compare_dir.empty()) {
      const fs::path reference = fs::path(compare_dir) / name / FrameName(frame);
      if (fs::exists(reference)) {
        const Image rgb = ToRgb8(ReadImage(reference.string()));
        if (rgb.width != mask.width || rgb.height != mask.height)
          throw InputError(reference.string(), "reference mask differs in size from the frames");
        std::size_t both = 0, either = 0;
        for (std::size_t i = 0; i < mask.data.size(); ++i) {
          const bool a = mask.data[i] != 0, b = rgb.data[3 * i] >= 128;
          both += a && b;
          either += a || b;
        }
        ious[static_cast<std::size_t>(camera) * (end - first) + (frame - first)] =
            either ? static_cast<double>(both) / either : 1.0;
      }
    }
    if (!options.overlays) return;
    char percent[32];
    std::snprintf(percent, sizeof percent, "  %.1f%%", 100.0 * summary.foreground_fraction);
    std::string label = name + percent;
    if (summary.empty) label += " EMPTY";
    if (summary.full) label += " FULL";
    if (summary.touches_border) label += " BORDER";
    if (summary.area_jump) label += " JUMP";
    if (summary.low_confidence) {
      std::snprintf(percent, sizeof percent, " LOW %.2f", summary.confidence);
      label += percent;
    }
    Image tile = DrawMaskOverlay(image, mask, options.overlay_width, label);
    std::vector<Image> ready;
    {
      std::lock_guard<std::mutex> lock(mutex);
      std::vector<Image>& tiles = pending[frame];
      if (tiles.empty()) tiles.resize(num_cameras);
      tiles[camera] = std::move(tile);
      if (std::all_of(tiles.begin(), tiles.end(), [](const Image& t) { return !t.empty(); })) {
        ready = std::move(tiles);
        pending.erase(frame);
      }
    }
    if (!ready.empty()) WriteImage((fs::path(overlay_dir) / FrameName(frame)).string(), TileImages(ready));
  };
  const SilhouetteSummary summary =
      ExtractSilhouettes(capture, first, end, options.silhouettes, sink, progress);

  nlohmann::json json = SummaryJson(capture, summary, first, end);
  const bool compared = std::any_of(ious.begin(), ious.end(), [](double iou) { return iou >= 0; });
  if (compared)
    for (std::size_t i = 0; i < ious.size(); ++i)
      if (ious[i] >= 0) json["masks"][i]["iou"] = ious[i];
  WriteTextFile((fs::path(out_dir) / "summary.json").string(), json.dump(1));
  char text[256];
  std::snprintf(text, sizeof text, "%-12s %-8s %10s %6s %6s %6s %6s %10s %6s %5s%s", "camera", "method", "mean fg %",
                "empty", "full", "border", "jump", "threshold", "conf", "low", compared ? "   mean IoU  worst IoU" : "");
  result.lines.push_back(text);
  const int frames = end - first;
  double all_iou_sum = 0, all_iou_worst = 1;
  int all_iou_count = 0;
  for (int c = 0; c < num_cameras; ++c) {
    double sum = 0;
    int empty = 0, full = 0, border = 0, jump = 0, low = 0;
    for (int f = 0; f < frames; ++f) {
      const MaskSummary& mask = summary.masks[static_cast<std::size_t>(c) * frames + f];
      sum += mask.foreground_fraction;
      empty += mask.empty;
      full += mask.full;
      border += mask.touches_border;
      jump += mask.area_jump;
      low += mask.low_confidence;
    }
    const CameraSilhouetteInfo& info = summary.cameras[c];
    // Green key: the greenness threshold; background models: the automatic threshold factor.
    char threshold[32];
    std::snprintf(threshold, sizeof threshold, info.method == SilhouetteMethod::kGreen ? "g %.3f"
                                               : info.method == SilhouetteMethod::kMog2 || info.method == SilhouetteMethod::kPerson
                                                   ? "-"
                                                   : "x %.2f",
                  info.method == SilhouetteMethod::kGreen ? info.greenness : info.threshold_scale);
    std::snprintf(text, sizeof text, "%-12s %-8s %10.2f %6d %6d %6d %6d %10s %6.3f %5d", info.name.c_str(),
                  SilhouetteMethodName(info.method), 100.0 * sum / frames, empty, full, border, jump, threshold,
                  summary.trust.camera_confidence.empty() ? 1.0 : summary.trust.camera_confidence[c], low);
    std::string line = text;
    double iou_sum = 0, iou_worst = 1;
    int iou_count = 0;
    for (int f = 0; f < frames; ++f) {
      const double iou = ious[static_cast<std::size_t>(c) * frames + f];
      if (iou < 0) continue;
      iou_sum += iou;
      iou_worst = std::min(iou_worst, iou);
      ++iou_count;
    }
    if (iou_count > 0) {
      std::snprintf(text, sizeof text, "   %9.4f  %9.4f", iou_sum / iou_count, iou_worst);
      line += text;
    }
    result.lines.push_back(line);
    all_iou_sum += iou_sum;
    all_iou_count += iou_count;
    all_iou_worst = std::min(all_iou_worst, iou_count ? iou_worst : 1.0);
  }
  if (all_iou_count > 0) {
    std::snprintf(text, sizeof text, "IoU against %s: mean %.4f, worst %.4f over %d camera-frames", compare_dir.c_str(),
                  all_iou_sum / all_iou_count, all_iou_worst, all_iou_count);
    result.lines.push_back(text);
  }
  result.extraction = summary;
  result.overlay_dir = options.overlays ? overlay_dir : "";
  result.summary_path = (fs::path(out_dir) / "summary.json").string();
  return result;
}

}  // namespace confluent
