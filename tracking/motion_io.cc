#include "tracking/motion_io.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tracking/shape_json.h"

namespace confluent {
using Eigen::Vector3d;

namespace {

const char* LimbSearchName(LimbSearch search) { return search == LimbSearch::kRan ? "ran" : "skipped"; }

LimbSearch ParseLimbSearch(const std::string& name, const std::string& path) {
  if (name.empty()) return LimbSearch::kNotTriggered;
  if (name == "ran") return LimbSearch::kRan;
  if (name == "skipped") return LimbSearch::kSkipped;
  throw InputError(path, "limb_search is '" + name + "', expected 'ran' or 'skipped'");
}

}  // namespace

void WritePosesJson(const std::string& path, const BodyTemplate& body, const BodyShape& shape,
                    const std::vector<std::string>& camera_names, const std::vector<TrackedFrame>& frames, double fps) {
  using nlohmann::json;
  json root;
  root["format"] = "confluent.poses/1";
  root["fps"] = fps;
  root["joint_names"] = body.joint_names();
  root["parents"] = std::vector<int>(body.parents().begin(), body.parents().end());
  root["joint_mapping"] = JointMappingNote();
  json dofs = json::array();
  for (int j = 0; j < kNumTemplateJoints; ++j) {
    const JointDof& d = body.dofs()[j];
    if (d.num_dof() == 0) continue;
    const char* type = d.type == JointType::kBall ? "ball_rotation_vector" : d.type == JointType::kHinge ? "hinge" : "hinge2";
    json entry = {{"joint", body.joint_names()[j]}, {"type", type}};
    std::vector<double> lo, hi;
    for (int k = 0; k < d.num_dof(); ++k) {
      lo.push_back(d.lower[k]);
      hi.push_back(d.upper[k]);
    }
    entry["lower_rad"] = lo;
    entry["upper_rad"] = hi;
    if (d.type != JointType::kBall) {
      entry["axes"] = json::array();
      for (int k = 0; k < d.num_dof(); ++k) entry["axes"].push_back({d.axes[k].x(), d.axes[k].y(), d.axes[k].z()});
    }
    dofs.push_back(entry);
  }
  root["dofs"] = dofs;
  root["shape"] = tracking_internal::BodyShapeJson(shape);
  json rest = json::array();
  for (const Vector3d& p : body.RestPositions(shape)) rest.push_back({p.x(), p.y(), p.z()});
  root["rest_joint_positions"] = rest;
  json list = json::array();
  for (const TrackedFrame& f : frames) {
    json jf;
    jf["frame"] = f.frame;
    jf["root_translation"] = {f.pose.root_translation.x(), f.pose.root_translation.y(), f.pose.root_translation.z()};
    jf["root_rotation_vector"] = {f.pose.root_rotation.x(), f.pose.root_rotation.y(), f.pose.root_rotation.z()};
    json angles;
    for (int j = 0; j < kNumTemplateJoints; ++j) {
      const int n = body.dofs()[j].num_dof();
      if (n == 0) continue;
      angles[body.joint_names()[j]] = std::vector<double>(f.pose.dofs[j].begin(), f.pose.dofs[j].begin() + n);
    }
    jf["joint_angles"] = angles;
    const Pose pose = body.ToPose(f.pose);
    json quats = json::array();
    for (const auto& q : pose.local_rotations) quats.push_back({q.w(), q.x(), q.y(), q.z()});
    jf["local_rotations_wxyz"] = quats;
    json positions = json::array();
    for (const Vector3d& p : f.joints) positions.push_back({p.x(), p.y(), p.z()});
    jf["joint_positions"] = positions;
    json iou;
    for (std::size_t c = 0; c < f.camera_iou.size() && c < camera_names.size(); ++c)
      if (f.camera_iou[c] >= 0) iou[camera_names[c]] = f.camera_iou[c];
    jf["camera_iou"] = iou;
    jf["mean_iou"] = f.mean_iou;
    jf["flags"] = f.flags;
    jf["fit"] = {{"iterations", f.fit.iterations},
                 {"final_cost", f.fit.final_cost},
                 {"mean_outside_px", f.fit.mean_outside_px},
                 {"mean_contour_px", f.fit.mean_contour_px},
                 {"cameras", f.fit.num_cameras},
                 {"seconds", f.fit.seconds}};
    jf["seconds"] = f.seconds;
    jf["cpu_seconds"] = f.cpu_seconds;
    if (f.limb_search != LimbSearch::kNotTriggered) jf["limb_search"] = LimbSearchName(f.limb_search);
    if (f.fruitless_search.pending())
      jf["fruitless_limb_search"] = {{"mean_iou", f.fruitless_search.mean_iou},
                                     {"mean_contour_px", f.fruitless_search.mean_contour_px}};
    list.push_back(jf);
  }
  root["frames"] = list;
  WriteTextFile(path, root.dump(1) + "\n");
}

PosesFile ReadPosesJson(const std::string& path, const BodyTemplate& body, const std::vector<std::string>& camera_names) {
  using nlohmann::json;
  PosesFile file;
  file.camera_names = camera_names;
  try {
    const json root = json::parse(ReadTextFile(path));
    file.fps = root.value("fps", 25.0);
    file.shape = tracking_internal::ParseBodyShapeJson(root.at("shape"), path);
    for (const json& jf : root.at("frames")) {
      TrackedFrame f;
      f.frame = jf.at("frame").get<int>();
      const auto t = jf.at("root_translation").get<std::vector<double>>();
      const auto r = jf.at("root_rotation_vector").get<std::vector<double>>();
      if (t.size() != 3 || r.size() != 3) throw InputError(path, "frame " + std::to_string(f.frame) + ": root needs 3 values");
      f.pose.root_translation = Vector3d(t[0], t[1], t[2]);
      f.pose.root_rotation = Vector3d(r[0], r[1], r[2]);
      for (const auto& [name, values] : jf.at("joint_angles").items()) {
        const auto it = std::find(body.joint_names().begin(), body.joint_names().end(), name);
        if (it == body.joint_names().end()) throw InputError(path, "unknown joint '" + name + "'");
        const int j = static_cast<int>(it - body.joint_names().begin());
        const auto angles = values.get<std::vector<double>>();
        // Files of the 37-DOF template (before 2026-12-02) give a wrist one angle, its flexion:
        // the same first axis, no deviation. (Their neck had no entry: upright, as it was.)
        const bool one_axis_wrist = body.dofs()[j].type == JointType::kHinge2 && angles.size() == 1 &&
                                    (j == kJointLeftWrist || j == kJointRightWrist);
        if (static_cast<int>(angles.size()) != body.dofs()[j].num_dof() && !one_axis_wrist)
          throw InputError(path, "joint '" + name + "' needs " + std::to_string(body.dofs()[j].num_dof()) + " angles");
        for (std::size_t k = 0; k < angles.size(); ++k) f.pose.dofs[j][k] = angles[k];
      }
      f.joints = body.JointPositions(file.shape, f.pose);
      f.mean_iou = jf.value("mean_iou", 0.0);
      f.flags = jf.value("flags", std::vector<std::string>{});
      f.seconds = jf.value("seconds", 0.0);
      f.cpu_seconds = jf.value("cpu_seconds", 0.0);
      f.limb_search = ParseLimbSearch(jf.value("limb_search", std::string()), path);
      if (jf.contains("fruitless_limb_search")) {
        f.fruitless_search.mean_iou = jf["fruitless_limb_search"].at("mean_iou").get<double>();
        f.fruitless_search.mean_contour_px = jf["fruitless_limb_search"].at("mean_contour_px").get<double>();
      }
      f.camera_iou.assign(camera_names.size(), -1.0);
      if (jf.contains("camera_iou"))
        for (std::size_t c = 0; c < camera_names.size(); ++c)
          if (jf["camera_iou"].contains(camera_names[c])) f.camera_iou[c] = jf["camera_iou"][camera_names[c]].get<double>();
      if (jf.contains("fit")) {
        f.fit.iterations = jf["fit"].value("iterations", 0);
        f.fit.final_cost = jf["fit"].value("final_cost", 0.0);
        f.fit.mean_outside_px = jf["fit"].value("mean_outside_px", 0.0);
        f.fit.mean_contour_px = jf["fit"].value("mean_contour_px", 0.0);
        f.fit.num_cameras = jf["fit"].value("cameras", 0);
        f.fit.seconds = jf["fit"].value("seconds", 0.0);
      }
      file.frames.push_back(std::move(f));
    }
  } catch (const json::exception& e) {
    throw InputError(path, std::string("not a poses.json: ") + e.what());
  }
  return file;
}

}  // namespace confluent
