// Reading and writing the template registration: the "template_registration" entry of
// correspondences.json (shape and pose encoded as in poses.json).

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tracking/scan_registration.h"
#include "tracking/shape_json.h"

namespace confluent {

using Eigen::Vector3d;

namespace {

nlohmann::json PoseJson(const BodyTemplate& body, const TemplatePose& pose) {
  nlohmann::json out;
  out["root_translation"] = {pose.root_translation.x(), pose.root_translation.y(), pose.root_translation.z()};
  out["root_rotation_vector"] = {pose.root_rotation.x(), pose.root_rotation.y(), pose.root_rotation.z()};
  nlohmann::json angles = nlohmann::json::object();
  for (int j = 0; j < kNumTemplateJoints; ++j) {
    const int n = body.dofs()[j].num_dof();
    if (n == 0) continue;
    angles[body.joint_names()[j]] = std::vector<double>(pose.dofs[j].begin(), pose.dofs[j].begin() + n);
  }
  out["joint_angles"] = angles;
  return out;
}

Vector3d Vec3(const nlohmann::json& value, const std::string& path, const std::string& what) {
  if (!value.is_array() || value.size() != 3) throw InputError(path, what + ": expected an array of 3 numbers");
  Vector3d v;
  for (int k = 0; k < 3; ++k) {
    if (!value[k].is_number()) throw InputError(path, what + ": expected an array of 3 numbers");
    v[k] = value[k].get<double>();
  }
  return v;
}

// Parses the pose `value`, named `what` in errors (its key in the file).
TemplatePose ParsePose(const BodyTemplate& body, const nlohmann::json& value, const std::string& path,
                       const std::string& what) {
  TemplatePose pose;
  if (!value.is_object()) throw InputError(path, what + ": expected an object");
  pose.root_translation = Vec3(value.value("root_translation", nlohmann::json()), path, what + ".root_translation");
  pose.root_rotation =
      Vec3(value.value("root_rotation_vector", nlohmann::json()), path, what + ".root_rotation_vector");
  const auto angles = value.value("joint_angles", nlohmann::json::object());
  for (int j = 0; j < kNumTemplateJoints; ++j) {
    const int n = body.dofs()[j].num_dof();
    const std::string& name = body.joint_names()[j];
    if (n == 0 || !angles.contains(name)) continue;
    const auto& a = angles[name];
    if (!a.is_array() || static_cast<int>(a.size()) != n) throw InputError(path, what + ".joint_angles: " + name + " needs " + std::to_string(n) + " values");
    for (int k = 0; k < n; ++k) {
      if (!a[k].is_number()) throw InputError(path, what + ".joint_angles: " + name + " must hold numbers");
      pose.dofs[j][k] = a[k].get<double>();
    }
  }
  return pose;
}

nlohmann::json ReadJson(const std::string& path) {
  const std::string text = ReadTextFile(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, std::string("not valid JSON: ") + e.what());
  }
}

}  // namespace

void WriteTemplateRegistration(const std::string& correspondences_path, const BodyTemplate& body,
                               const ScanRegistration& registration) {
  nlohmann::json root = ReadJson(correspondences_path);
  nlohmann::json reg;
  reg["format"] = "confluent.template_registration/1";
  reg["shape"] = tracking_internal::BodyShapeJson(registration.shape);
  reg["pose"] = PoseJson(body, registration.pose);
  reg["rms_residual"] = registration.rms_residual_m;
  reg["trimmed_rms_residual"] = registration.trimmed_rms_residual_m;
  reg["scan_height"] = registration.scan_height;
  reg["metres_per_unit"] = registration.metres_per_unit;
  reg["up_in_scan"] = {registration.up_in_scan.x(), registration.up_in_scan.y(), registration.up_in_scan.z()};
  reg["warnings"] = registration.warnings;
  if (registration.first_tracked_pose) reg["first_tracked_pose"] = PoseJson(body, *registration.first_tracked_pose);
  root["template_registration"] = reg;
  WriteTextFile(correspondences_path, root.dump(1) + "\n");
}

bool HasTemplateRegistration(const std::string& correspondences_path) {
  const nlohmann::json root = ReadJson(correspondences_path);
  return root.is_object() && root.contains("template_registration");
}

ScanRegistration ReadTemplateRegistration(const std::string& correspondences_path, const BodyTemplate& body) {
  const nlohmann::json root = ReadJson(correspondences_path);
  if (!root.is_object() || !root.contains("template_registration"))
    throw InputError(correspondences_path, "no \"template_registration\" (write it with confluent correspond)");
  const auto& reg = root["template_registration"];
  ScanRegistration result;
  result.shape = tracking_internal::ParseBodyShapeJson(reg.value("shape", nlohmann::json()), correspondences_path);
  result.pose = ParsePose(body, reg.value("pose", nlohmann::json()), correspondences_path, "template_registration.pose");
  result.rms_residual_m = reg.value("rms_residual", 0.0);
  result.trimmed_rms_residual_m = reg.value("trimmed_rms_residual", 0.0);
  result.scan_height = reg.value("scan_height", 0.0);
  result.metres_per_unit = reg.value("metres_per_unit", 1.0);
  if (reg.contains("up_in_scan")) result.up_in_scan = Vec3(reg["up_in_scan"], correspondences_path, "up_in_scan");
  if (reg.contains("first_tracked_pose"))
    result.first_tracked_pose =
        ParsePose(body, reg["first_tracked_pose"], correspondences_path, "template_registration.first_tracked_pose");
  if (reg.contains("warnings") && reg["warnings"].is_array())
    for (const auto& w : reg["warnings"])
      if (w.is_string()) result.warnings.push_back(w.get<std::string>());
  return result;
}

}  // namespace confluent
