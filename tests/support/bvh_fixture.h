#pragma once
// A synthetic CMU-named BVH (Y up, centimetres, T-pose facing +z, its left at +x) with frames of
// known joint rotations, shared by the retargeting, studio and animate tests.

#include <Eigen/Core>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace confluent::testing::bvh_fixture {

using Eigen::Vector3d;

// A CMU-named, Y-up, centimetre BVH in a T-pose facing +z (its left is +x). `names` may rename
// joints (for the unmappable case); `hand_cm` is the length of the hands' End Sites (0: a hand
// that ends where it starts, as in Bandai Namco's files).
inline std::string SyntheticBvh(const std::vector<std::string>& frames, const std::map<std::string, std::string>& rename = {},
                                double hand_cm = 18) {
  auto n = [&](const std::string& name) {
    const auto it = rename.find(name);
    return it == rename.end() ? name : it->second;
  };
  std::ostringstream s;
  auto joint = [&](const std::string& name, const Vector3d& offset) {
    s << "JOINT " << n(name) << "\n{\nOFFSET " << offset.x() << " " << offset.y() << " " << offset.z()
      << "\nCHANNELS 3 Zrotation Yrotation Xrotation\n";
  };
  auto end = [&](const Vector3d& offset) {
    s << "End Site\n{\nOFFSET " << offset.x() << " " << offset.y() << " " << offset.z() << "\n}\n";
  };
  s << "HIERARCHY\nROOT " << n("Hips") << "\n{\nOFFSET 0 95 0\n"
    << "CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n";
  for (const double sx : {1.0, -1.0}) {
    const std::string side = sx > 0 ? "Left" : "Right";
    joint(side + "UpLeg", {sx * 10, -5, 0});
    joint(side + "Leg", {0, -42, 0});
    joint(side + "Foot", {0, -42, 0});
    joint(side + "ToeBase", {0, -5, 12});
    end({0, 0, 4});
    s << "}\n}\n}\n}\n";
  }
  joint("Spine", {0, 12, 0});
  joint("Spine1", {0, 15, 0});
  joint("Neck", {0, 18, 0});
  joint("Head", {0, 10, 0});
  end({0, 18, 0});
  s << "}\n}\n";
  for (const double sx : {1.0, -1.0}) {
    const std::string side = sx > 0 ? "Left" : "Right";
    joint(side + "Arm", {sx * 18, 14, 0});
    joint(side + "ForeArm", {sx * 28, 0, 0});
    joint(side + "Hand", {sx * 25, 0, 0});
    end({sx * hand_cm, 0, 0});
    s << "}\n}\n}\n";
  }
  s << "}\n}\n}\nMOTION\nFrames: " << frames.size() << "\nFrame Time: 0.02\n";
  for (const std::string& frame : frames) s << frame << "\n";
  return s.str();
}

// Channel order: Hips (6), then per joint 3 (Z Y X) in file order:
// LeftUpLeg LeftLeg LeftFoot LeftToeBase RightUpLeg RightLeg RightFoot RightToeBase Spine Spine1
// Neck Head LeftArm LeftForeArm LeftHand RightArm RightForeArm RightHand.
constexpr int kBvhJoints = 19;
inline std::string Frame(const Vector3d& root, const std::map<int, Vector3d>& zyx_deg) {
  std::ostringstream s;
  s << root.x() << " " << root.y() << " " << root.z();
  for (int j = 0; j < kBvhJoints; ++j) {
    const auto it = zyx_deg.find(j);
    const Vector3d v = it == zyx_deg.end() ? Vector3d::Zero() : it->second;
    s << " " << v.x() << " " << v.y() << " " << v.z();
  }
  return s.str();
}
enum { kHips = 0, kLUpLeg, kLLeg, kLFoot, kLToe, kRUpLeg, kRLeg, kRFoot, kRToe, kSpine, kSpine1, kNeck, kHead,
       kLArm, kLForeArm, kLHand, kRArm, kRForeArm, kRHand };

inline std::vector<std::string> TestFrames() {
  return {Frame({0, 0, 0}, {}),
          // Left arm down, forearm bent forwards, left thigh forwards, right knee bent, head turned.
          Frame({10, 0, 0}, {{kLArm, {-90, 0, 0}}, {kLForeArm, {0, -90, 0}}, {kLUpLeg, {0, 0, -45}},
                             {kRLeg, {0, 0, 60}}, {kHead, {0, 30, 0}}}),
          // A turn of the whole body, a spine bend, a forearm twist about its own axis.
          Frame({-5, -20, 8}, {{kHips, {0, 70, 0}}, {kSpine, {0, 0, 25}}, {kLForeArm, {0, 0, 40}},
                               {kRArm, {30, 20, 10}}, {kRForeArm, {10, -50, 0}}, {kLFoot, {0, 0, 30}}})};
}

}  // namespace confluent::testing::bvh_fixture
