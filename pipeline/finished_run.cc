#include "pipeline/finished_run.h"

#include <algorithm>
#include <filesystem>

#include "core/error.h"

namespace confluent {
namespace fs = std::filesystem;

std::vector<std::string> FinishedRun::HeldOutCameras() const {
  return manifest ? manifest->held_out_cameras : std::vector<std::string>{};
}

double FinishedRun::fps() const { return manifest && manifest->fps > 0.0 ? manifest->fps : kAssumedFrameRate; }

FinishedRun OpenFinishedRun(const std::string& root, const std::string& capture_root) {
  std::error_code error;
  if (!fs::is_directory(root, error)) throw InputError(root, "run folder not found");
  FinishedRun run;
  run.folder.root = root;
  const std::string manifest_path = RunManifestPath(root);
  if (fs::exists(manifest_path, error)) run.manifest = ReadRunManifest(manifest_path);
  run.capture_root = capture_root;
  if (run.capture_root.empty() && run.manifest) run.capture_root = run.manifest->capture;
  if (run.capture_root.empty())
    throw UsageError("CAPTURE: not given, and " + manifest_path +
                     (run.manifest ? " names no capture" : " does not exist") + "; give the capture folder");
  return run;
}

std::vector<std::string> TexturingExclusions(const FinishedRun& run, const Rig& rig, std::vector<std::string> excluded,
                                             bool texture_from_held_out, std::string* warning) {
  for (const std::string& name : excluded) rig.Get(name);  // UsageError listing the known names
  std::vector<std::string> held_out_used;
  for (const std::string& name : run.HeldOutCameras()) {
    if (rig.IndexOf(name) < 0 || std::find(excluded.begin(), excluded.end(), name) != excluded.end()) continue;
    if (texture_from_held_out)
      held_out_used.push_back(name);
    else
      excluded.push_back(name);
  }
  if (warning != nullptr && !held_out_used.empty()) {
    std::string names;
    for (const std::string& name : held_out_used) names += (names.empty() ? "" : ", ") + name;
    *warning = "texturing from camera(s) the run held out (" + names +
               "): a view of a held-out camera textured from itself proves nothing about the run";
  }
  const auto is_excluded = [&](const Camera& camera) {
    return std::find(excluded.begin(), excluded.end(), camera.name) != excluded.end();
  };
  if (std::all_of(rig.cameras.begin(), rig.cameras.end(), is_excluded))
    throw UsageError("--exclude-camera: no camera is left for texturing");
  return excluded;
}

TexturingCameras SelectTexturingCameras(const FinishedRun& run, const Rig& rig, const std::vector<std::string>& excluded,
                                        bool texture_from_held_out, std::string* warning) {
  const std::vector<std::string> all_excluded = TexturingExclusions(run, rig, excluded, texture_from_held_out, warning);
  TexturingCameras result;
  for (int c = 0; c < rig.size(); ++c)
    if (std::find(all_excluded.begin(), all_excluded.end(), rig.cameras[c].name) == all_excluded.end()) {
      result.indices.push_back(c);
      result.cameras.push_back(rig.cameras[c]);
    }
  return result;
}

void ReadTexturingFrame(const FinishedRun& run, const Capture& capture, const TexturingCameras& cameras, int frame,
                        std::vector<Image>* images, std::vector<Image>* masks) {
  images->clear();
  masks->clear();
  bool any_mask = false;
  for (int c : cameras.indices) {
    images->push_back(capture.ReadFrame(c, frame));
    const std::string run_mask = run.folder.MaskPath(capture.rig().cameras[c].name, frame);
    if (std::filesystem::exists(run_mask))
      masks->push_back(ReadMaskFile(run_mask));
    else if (capture.has_masks() && std::filesystem::exists(capture.MaskPath(c, frame)))
      masks->push_back(capture.ReadMask(c, frame));
    else
      masks->push_back(Image());
    any_mask = any_mask || !masks->back().empty();
  }
  if (!any_mask) masks->clear();
}

}  // namespace confluent
