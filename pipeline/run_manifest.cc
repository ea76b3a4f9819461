#include "pipeline/run_manifest.h"

#include <filesystem>

#include "calib/capture.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {

double RunFrameRate(const Capture& capture, double requested) {
  if (requested > 0.0) return requested;
  return capture.frame_rate() > 0.0 ? capture.frame_rate() : kAssumedFrameRate;
}

std::string RunManifestPath(const std::string& root) { return (std::filesystem::path(root) / "run.json").string(); }

RunManifest ReadRunManifest(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error))
    throw InputError(path, "not found: not a run folder (make one with: confluent run CAPTURE --out RUN)");
  RunManifest manifest;
  try {
    const nlohmann::json json = nlohmann::json::parse(ReadTextFile(path));
    if (!json.is_object()) throw InputError(path, "not a run.json: expected a JSON object");
    manifest.version = json.value("version", manifest.version);
    manifest.capture = json.value("capture", manifest.capture);
    manifest.scan = json.value("scan", manifest.scan);
    manifest.correspondences = json.value("correspondences", manifest.correspondences);
    manifest.masks = json.value("masks", manifest.masks);
    manifest.held_out_cameras = json.value("excluded_cameras", manifest.held_out_cameras);
    const std::vector<int> frames = json.value("frames", std::vector<int>{0, 0});
    if (frames.size() != 2 || frames[0] < 0 || frames[1] < frames[0])
      throw InputError(path, "\"frames\" must be [first, end) with 0 <= first <= end");
    manifest.frames = {frames[0], frames[1]};
    manifest.fps = json.value("fps", manifest.fps);
    if (!(manifest.fps >= 0.0 && manifest.fps <= 1000.0)) throw InputError(path, "\"fps\" must be within [0, 1000]");
    manifest.options = json.value("options", manifest.options);
    if (!manifest.options.is_object()) throw InputError(path, "\"options\" must be an object");
    manifest.input_checksums = json.value("input_checksums", nlohmann::json());
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, std::string("not a run.json: ") + e.what());
  }
  return manifest;
}

void WriteRunManifest(const std::string& path, const RunManifest& manifest) {
  nlohmann::json json;
  json["format"] = "confluent.run/1";
  json["version"] = manifest.version;
  json["capture"] = manifest.capture;
  json["scan"] = manifest.scan;
  json["correspondences"] = manifest.correspondences;
  json["masks"] = manifest.masks;
  json["excluded_cameras"] = manifest.held_out_cameras;
  json["frames"] = {manifest.frames.first, manifest.frames.end};
  json["fps"] = manifest.fps;
  json["options"] = manifest.options;
  json["input_checksums"] = manifest.input_checksums;
  WriteTextFile(path, json.dump(1) + "\n");
}

}  // namespace confluent
