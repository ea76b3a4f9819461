#pragma once
// A run folder as the commands that read a finished run open it (render, evaluate): the folder,
// its manifest when it has one, and the capture it was made from.

#include <optional>
#include <string>
#include <vector>

#include "calib/camera.h"
#include "calib/capture.h"
#include "core/image.h"
#include "pipeline/run_folder.h"
#include "pipeline/run_manifest.h"

namespace confluent {

struct FinishedRun {
  RunFolder folder;
  std::optional<RunManifest> manifest;  // absent when the folder has no run.json
  std::string capture_root;             // the capture given, else the one run.json names

  // The cameras the run held out (none without a manifest).
  std::vector<std::string> HeldOutCameras() const;
  // The run's frame rate, else kAssumedFrameRate.
  double fps() const;
};

// Opens run folder `root`; `capture_root` (when not empty) replaces the capture run.json names.
// Throws InputError when the folder is missing or run.json is unreadable, and UsageError when
// no capture is given and run.json names none.
FinishedRun OpenFinishedRun(const std::string& root, const std::string& capture_root);

// The cameras of `rig` that texture a view of the run: all but `excluded` and, unless
// `texture_from_held_out`, all but the run's held-out cameras. Throws UsageError naming an
// unknown camera, or when none is left. `*warning` (when given) receives a line when the view
// is textured from cameras the run held out.
std::vector<std::string> TexturingExclusions(const FinishedRun& run, const Rig& rig, std::vector<std::string> excluded,
                                             bool texture_from_held_out, std::string* warning);

// The cameras that texture a view of the run (TexturingExclusions' complement), in rig order.
struct TexturingCameras {
  std::vector<int> indices;      // into the rig
  std::vector<Camera> cameras;   // copies, for ProjectiveTexturer::SetFrame
};

// TexturingExclusions, returned as the cameras that remain. Throws as it does.
TexturingCameras SelectTexturingCameras(const FinishedRun& run, const Rig& rig, const std::vector<std::string>& excluded,
                                        bool texture_from_held_out, std::string* warning);

// The images of `frame` from the texturing cameras, and their masks: the run's (RUN/masks/),
// else the capture's, else an empty Image; `masks` is left empty when no camera has one.
// Throws InputError naming an unreadable file.
void ReadTexturingFrame(const FinishedRun& run, const Capture& capture, const TexturingCameras& cameras, int frame,
                        std::vector<Image>* images, std::vector<Image>* masks);

}  // namespace confluent
