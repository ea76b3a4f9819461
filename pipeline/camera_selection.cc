#include "pipeline/camera_selection.h"

#include <algorithm>

#include "core/error.h"

namespace confluent {

CameraSelection::CameraSelection(const Rig& rig) : held_out_(rig.size(), false) {}

CameraSelection::CameraSelection(const Rig& rig, const std::vector<std::string>& held_out) : CameraSelection(rig) {
  for (const std::string& name : held_out) {
    rig.Get(name);  // throws UsageError listing the known names
    held_out_[rig.IndexOf(name)] = true;
  }
  held_out_names_ = held_out;
  std::sort(held_out_names_.begin(), held_out_names_.end());
  held_out_names_.erase(std::unique(held_out_names_.begin(), held_out_names_.end()), held_out_names_.end());
}

int CameraSelection::num_used() const {
  return static_cast<int>(std::count(held_out_.begin(), held_out_.end(), false));
}

std::vector<int> CameraSelection::used() const {
  std::vector<int> indices;
  for (int c = 0; c < num_cameras(); ++c)
    if (!held_out_[c]) indices.push_back(c);
  return indices;
}

std::vector<int> CameraSelection::held_out() const {
  std::vector<int> indices;
  for (int c = 0; c < num_cameras(); ++c)
    if (held_out_[c]) indices.push_back(c);
  return indices;
}

std::vector<Camera> CameraSelection::UsedCameras(const Rig& rig) const {
  std::vector<Camera> cameras;
  for (int c : used()) cameras.push_back(rig.cameras.at(c));
  return cameras;
}

void CameraSelection::RequireUsed(int minimum, const std::string& option) const {
  if (num_used() < minimum)
    throw UsageError(option + ": at least " + std::to_string(minimum) + " camera(s) must remain in use, " +
                     std::to_string(num_used()) + " of " + std::to_string(num_cameras()) + " do");
}

}  // namespace confluent
