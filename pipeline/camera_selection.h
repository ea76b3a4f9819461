#pragma once
// Which cameras of a rig a run uses and which it holds out for evaluation. Held-out cameras are
// never used to track, refine or texture; the selection travels as this one type from the
// command line through every stage and into run.json.

#include <string>
#include <vector>

#include "calib/camera.h"

namespace confluent {

class CameraSelection {
 public:
  CameraSelection() = default;
  // Every camera of `rig` used, none held out.
  explicit CameraSelection(const Rig& rig);
  // `held_out` names cameras of `rig` (repeats are ignored). Throws UsageError naming an unknown
  // camera and listing the rig's names.
  CameraSelection(const Rig& rig, const std::vector<std::string>& held_out);

  int num_cameras() const { return static_cast<int>(held_out_.size()); }
  int num_used() const;
  bool is_held_out(int camera) const { return held_out_.at(camera); }
  bool is_used(int camera) const { return !held_out_.at(camera); }
  std::vector<int> used() const;      // rig indices, ascending
  std::vector<int> held_out() const;  // rig indices, ascending
  // The held-out cameras' names in alphabetical order (as run.json records them).
  const std::vector<std::string>& held_out_names() const { return held_out_names_; }
  // Per rig camera: held out (the form the tracker takes).
  const std::vector<bool>& held_out_mask() const { return held_out_; }
  // The used cameras of `rig` (the rig this selection was made for), in rig order.
  std::vector<Camera> UsedCameras(const Rig& rig) const;
  // Throws UsageError naming `option` when fewer than `minimum` cameras remain in use.
  void RequireUsed(int minimum, const std::string& option) const;

 private:
  std::vector<bool> held_out_;
  std::vector<std::string> held_out_names_;
};

}  // namespace confluent
