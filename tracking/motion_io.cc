#include "tracking/motion_io.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// World (Z up) -> BVH (Y up): (x, y, z) -> (x, z, -y).
Matrix3d BvhFromWorld() {
  Matrix3d M;
  M << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return M;
}

std::string Num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6f", std::abs(v) < 5e-7 ? 0.0 : v);
  return buffer;
}

}  // namespace

void WriteBvh(const std::string& path, const Skeleton& skeleton, const std::vector<Pose>& poses, double frame_time_s) {
  const Matrix3d M = BvhFromWorld();
  const int n = skeleton.size();
  std::vector<std::vector<int>> children(n);
  for (int j = 1; j < n; ++j) children[skeleton.joints[j].parent].push_back(j);
  std::vector<int> channel_joints;  // joints with channels, in file order
  std::ostringstream out;
  out << "HIERARCHY\n";
  std::function<void(int, int)> write = [&](int j, int depth) {
    const std::string indent(2 * depth, ' ');
    const Vector3d offset = 100.0 * M * skeleton.joints[j].offset_in_parent;
    if (j != 0 && children[j].empty()) {
      out << indent << "End Site\n" << indent << "{\n"
          << indent << "  OFFSET " << Num(offset.x()) << " " << Num(offset.y()) << " " << Num(offset.z()) << "\n"
          << indent << "}\n";
      return;
    }
    out << indent << (j == 0 ? "ROOT " : "JOINT ") << skeleton.joints[j].name << "\n" << indent << "{\n";
    out << indent << "  OFFSET " << Num(offset.x()) << " " << Num(offset.y()) << " " << Num(offset.z()) << "\n";
    out << indent << "  CHANNELS " << (j == 0 ? "6 Xposition Yposition Zposition " : "3 ") << "Zrotation Xrotation Yrotation\n";
    channel_joints.push_back(j);
    for (int c : children[j]) write(c, depth + 1);
    out << indent << "}\n";
  };
  write(0, 0);
  out << "MOTION\nFrames: " << poses.size() << "\nFrame Time: " << Num(frame_time_s) << "\n";
  for (const Pose& pose : poses) {
    const Vector3d t = 100.0 * M * pose.root_translation;
    out << Num(t.x()) << " " << Num(t.y()) << " " << Num(t.z());
    for (int j : channel_joints) {
      const Matrix3d R = j < static_cast<int>(pose.local_rotations.size()) ? pose.local_rotations[j].toRotationMatrix()
                                                                            : Matrix3d::Identity();
      const Vector3d euler = (M * R * M.transpose()).eulerAngles(2, 0, 1) * (180.0 / M_PI);
      out << " " << Num(euler(0)) << " " << Num(euler(1)) << " " << Num(euler(2));
    }
    out << "\n";
  }
  WriteTextFile(path, out.str());
}

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
  json length, girth;
  for (int s = 0; s < kNumBodySegments; ++s) {
    length[BodySegmentName(s)] = shape.length_scale[s];
    girth[BodySegmentName(s)] = shape.girth_scale[s];
  }
  root["shape"] = {{"length_scale", length}, {"girth_scale", girth}};
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
                 {"cameras", f.fit.num_cameras}};
    jf["seconds"] = f.seconds;
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
    const json& shape = root.at("shape");
    for (int s = 0; s < kNumBodySegments; ++s) {
      file.shape.length_scale[s] = shape.at("length_scale").at(BodySegmentName(s)).get<double>();
      file.shape.girth_scale[s] = shape.at("girth_scale").at(BodySegmentName(s)).get<double>();
    }
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
        if (static_cast<int>(angles.size()) != body.dofs()[j].num_dof())
          throw InputError(path, "joint '" + name + "' needs " + std::to_string(body.dofs()[j].num_dof()) + " angles");
        for (std::size_t k = 0; k < angles.size(); ++k) f.pose.dofs[j][k] = angles[k];
      }
      f.joints = body.JointPositions(file.shape, f.pose);
      f.mean_iou = jf.value("mean_iou", 0.0);
      f.flags = jf.value("flags", std::vector<std::string>{});
      f.seconds = jf.value("seconds", 0.0);
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
      }
      file.frames.push_back(std::move(f));
    }
  } catch (const json::exception& e) {
    throw InputError(path, std::string("not a poses.json: ") + e.what());
  }
  return file;
}

}  // namespace confluent
