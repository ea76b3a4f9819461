#include "core/bvh_retarget.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/body_model.h"
#include "core/error.h"

namespace confluent {
namespace {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

// Lower case, letters and digits only, without common rig prefixes ("mixamorig:", "Bip01 ").
std::string Normalize(const std::string& name) {
  std::string out;
  for (const char c : name)
    if (std::isalnum(static_cast<unsigned char>(c))) out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (const char* prefix : {"mixamorig", "bip001", "bip01"}) {
    const std::string p = prefix;
    if (out.size() > p.size() && out.compare(0, p.size(), p) == 0) out = out.substr(p.size());
  }
  return out;
}

// Name bases per target joint, best first. Sided joints are matched as <side><base> and
// <base><side> with side = left/l or right/r ("LeftUpLeg", "lThigh", "upperleg01.L").
struct NameRule {
  const char* target;  // without the side prefix for sided joints
  bool sided;
  std::vector<const char*> bases;
};

const std::vector<NameRule>& NameRules() {
  static const std::vector<NameRule> rules = {
      {"pelvis", false, {"hips", "hip", "pelvis", "root"}},
      {"neck", false, {"neck", "neck01", "lowerneck", "neck1"}},
      {"head", false, {"head"}},
      {"head_end", false, {"headend", "headtop", "headtopend", "headtopendend"}},
      {"shoulder", true, {"arm", "upperarm", "upperarm01", "shldr", "uparm", "humerus", "shoulder"}},
      {"elbow", true, {"forearm", "elbow", "lowerarm", "lowerarm01", "radius"}},
      {"wrist", true, {"wrist", "hand"}},
      {"hand_end", true, {"handend", "fingers", "fingerbase", "handmiddle1", "middle1", "mid1", "handindex1", "index1",
                          "finger31", "wristend", "fingersend"}},
      {"hip", true, {"upleg", "thigh", "upperleg", "upperleg01", "femur", "hip"}},
      {"knee", true, {"leg", "knee", "shin", "lowerleg", "lowerleg01", "calf", "tibia"}},
      {"ankle", true, {"foot", "ankle"}},
      {"toe", true, {"toebase", "toe", "toes", "toe1", "toe11", "footend", "ankleend"}},
  };
  return rules;
}

// The joints a BVH must provide (the others may follow their parents).
std::vector<std::string> EssentialJoints() {
  std::vector<std::string> names;
  for (BodyJoint joint : {kJointPelvis, kJointLeftShoulder, kJointLeftElbow, kJointLeftWrist, kJointRightShoulder,
                          kJointRightElbow, kJointRightWrist, kJointLeftHip, kJointLeftKnee, kJointLeftAnkle,
                          kJointRightHip, kJointRightKnee, kJointRightAnkle})
    names.push_back(BodyJointNames()[joint]);
  return names;
}

// The turn about `upper` (the upper arm's unit direction at the target's rest) that takes the
// elbow's mean flexion axis over `poses` onto the target's hinge, the body's `lateral` axis made
// perpendicular to the bone (the tracking template's elbow hinge). 0 when the elbow bends past
// 20 degrees in fewer than 10 frames, or its axis wanders (the mean of the unit axes shorter than
// 0.8: not a hinge).
double ElbowHingeTurn(const std::vector<Pose>& poses, int elbow, const Vector3d& upper, const Vector3d& lateral) {
  constexpr double kMinBendRad = 20.0 * M_PI / 180.0;
  constexpr int kMinBentFrames = 10;
  constexpr double kMinMeanAxisLength = 0.8;
  Vector3d sum = Vector3d::Zero();
  int bent = 0;
  for (const Pose& pose : poses) {
    const Eigen::AngleAxisd bend(pose.local_rotations[elbow]);
    if (bend.angle() < kMinBendRad) continue;
    sum += bend.axis();
    ++bent;
  }
  if (bent < kMinBentFrames || sum.norm() < kMinMeanAxisLength * bent) return 0.0;
  const Vector3d axis = (sum - sum.dot(upper) * upper).normalized();
  Vector3d hinge = lateral - lateral.dot(upper) * upper;
  if (!(axis.allFinite() && hinge.norm() > 1e-9)) return 0.0;
  hinge.normalize();
  if (hinge.dot(axis) < 0) hinge = -hinge;  // the shorter turn: flexion stays towards the front
  return std::atan2(hinge.cross(axis).dot(upper), hinge.dot(axis));
}

// The rotation R that best maps the unit vectors `from` onto `to` (Kabsch). A single pair or
// collinear vectors leave the twist about them open: then the rotation nearest `prior` (the
// minimal swing after `prior`). Empty input: identity.
Matrix3d BestRotation(const std::vector<Vector3d>& from, const std::vector<Vector3d>& to,
                      const Matrix3d& prior = Matrix3d::Identity()) {
  if (from.empty()) return Matrix3d::Identity();
  auto swing_after_prior = [&]() -> Matrix3d { return Quaterniond::FromTwoVectors(prior * from[0], to[0]).toRotationMatrix() * prior; };
  if (from.size() == 1) return swing_after_prior();
  Matrix3d h = Matrix3d::Zero();
  for (std::size_t i = 0; i < from.size(); ++i) h += from[i] * to[i].transpose();
  const Eigen::JacobiSVD<Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (svd.singularValues()(1) < 1e-6 * svd.singularValues()(0)) return swing_after_prior();
  Matrix3d d = Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixV() * d * svd.matrixU().transpose();
}

// World transforms of the BVH pose that defines its up axis, height and bone alignment: the rest
// pose when the body stands in it (the trunk opposite both legs), else the first frame in which it
// stands, else frame 0. Most files stand at rest (a T-pose); some exporters leave the rest pose
// meaningless (Bandai Namco's: every bone along +x) and pose the body only through the frames.
std::vector<Eigen::Isometry3d> ReferencePose(const BvhMotion& motion, int pelvis, int top, const int hips[2],
                                             const int ankles[2], int* frame) {
  auto stands = [&](const std::vector<Eigen::Isometry3d>& world) {
    const Vector3d trunk = world[top].translation() - world[pelvis].translation();
    for (int side = 0; side < 2; ++side) {
      const Vector3d leg = world[ankles[side]].translation() - world[hips[side]].translation();
      if (trunk.norm() <= 0 || leg.norm() <= 0 || trunk.normalized().dot(leg.normalized()) > -0.8) return false;
    }
    return true;
  };
  *frame = -1;
  std::vector<Eigen::Isometry3d> world = WorldFromJoint(motion.skeleton, Pose::Rest(motion.skeleton.size()));
  if (stands(world)) return world;
  for (std::size_t f = 0; f < motion.frames.size(); ++f) {
    world = WorldFromJoint(motion.skeleton, motion.frames[f]);
    if (stands(world)) {
      *frame = static_cast<int>(f);
      return world;
    }
  }
  *frame = 0;
  return WorldFromJoint(motion.skeleton, motion.frames[0]);
}

struct UnitGuess {
  const char* name;
  double metres;
};

}  // namespace

void BvhRetargetOptions::Check() const {
  if (up_axis != 'a' && up_axis != 'y' && up_axis != 'z')
    throw UsageError(std::string("BvhRetargetOptions.up_axis = '") + up_axis + "': must be 'a' (auto), 'y' or 'z'");
  RequireOption(min_hinge_turn_rad >= 0, "BvhRetargetOptions.min_hinge_turn_rad", min_hinge_turn_rad, ">= 0");
}

std::map<std::string, std::string> GuessBvhJointMap(const Skeleton& bvh, const std::vector<std::string>& target_names,
                                                    const std::vector<Vector3d>& joint_positions) {
  std::map<std::string, int> by_name;  // normalized BVH name -> first joint
  for (int j = 0; j < bvh.size(); ++j) by_name.emplace(Normalize(bvh.joints[j].name), j);
  auto has_target = [&](const std::string& name) {
    return std::find(target_names.begin(), target_names.end(), name) != target_names.end();
  };
  std::map<std::string, std::string> map;
  for (const NameRule& rule : NameRules()) {
    for (int side = 0; side < (rule.sided ? 2 : 1); ++side) {
      const std::string target = rule.sided ? std::string(side == 0 ? "left_" : "right_") + rule.target : rule.target;
      if (!has_target(target)) continue;
      std::vector<std::string> sides;
      if (rule.sided) sides = side == 0 ? std::vector<std::string>{"left", "l"} : std::vector<std::string>{"right", "r"};
      for (const char* base : rule.bases) {
        std::vector<std::string> forms;
        if (rule.sided)
          for (const std::string& s : sides) forms.push_back(s + base), forms.push_back(std::string(base) + s);
        else
          forms.push_back(base);
        bool found = false;
        for (const std::string& form : forms) {
          const auto it = by_name.find(form);
          if (it != by_name.end()) {
            map[target] = bvh.joints[it->second].name;
            found = true;
            break;
          }
        }
        if (found) break;
      }
    }
  }
  // No head joint, but a neck chain of two (CMU's ASF export: LowerNeck -> Neck): the upper one
  // turns the head.
  if (!map.count("head") && map.count("neck") && has_target("head")) {
    const int neck = bvh.IndexOf(map["neck"]), parent = bvh.joints[neck].parent;
    if (parent >= 0 && Normalize(bvh.joints[parent].name).find("neck") != std::string::npos) {
      map["head"] = map["neck"];
      map["neck"] = bvh.joints[parent].name;
    }
  }
  // End joints without a name of their own ("Hand_L_end"): the only child of the mapped joint
  // when it is an End Site (ReadBvh names them "<joint>_end").
  for (const auto& [end, joint] : {std::pair<const char*, const char*>{"head_end", "head"},
                                   {"left_hand_end", "left_wrist"}, {"right_hand_end", "right_wrist"}}) {
    if (map.count(end) || !map.count(joint) || !has_target(end)) continue;
    const int j = bvh.IndexOf(map[joint]);
    std::vector<int> kids;
    for (int c = 0; c < bvh.size(); ++c)
      if (bvh.joints[c].parent == j) kids.push_back(c);
    if (kids.size() == 1 && bvh.joints[kids[0]].name == map[joint] + "_end") map[end] = bvh.joints[kids[0]].name;
  }
  // Spine and chest: the joints of the pelvis-to-neck chain nearest the target's height fractions
  // (name conventions for the torso differ too much between rigs).
  const auto pelvis = map.find("pelvis");
  auto top = map.find("neck");
  if (top == map.end()) top = map.find("head");
  if (pelvis != map.end() && top != map.end() && (has_target("spine") || has_target("chest"))) {
    const int p = bvh.IndexOf(pelvis->second);
    std::vector<int> chain;  // from just below the top down to just above the pelvis
    int j = bvh.joints[bvh.IndexOf(top->second)].parent;
    while (j >= 0 && j != p) chain.push_back(j), j = bvh.joints[j].parent;
    if (j == p) {
      std::reverse(chain.begin(), chain.end());
      const std::vector<Vector3d> rest = joint_positions.empty() ? bvh.RestPositions() : joint_positions;
      const Vector3d base = rest[p], axis = rest[bvh.IndexOf(top->second)] - base;
      auto fraction = [&](int joint) { return axis.squaredNorm() > 0 ? (rest[joint] - base).dot(axis) / axis.squaredNorm() : 0.0; };
      // The studio skeleton's fractions (spine 0.28, chest 0.65 of pelvis -> neck).
      const double want[2] = {0.28, 0.65};
      const char* names[2] = {"spine", "chest"};
      double last = 0.05;
      for (int k = 0; k < 2; ++k) {
        int best = -1;
        double best_error = std::numeric_limits<double>::max();
        for (int joint : chain) {
          const double f = fraction(joint);
          if (f <= last + 1e-6 || f >= 0.95) continue;
          if (std::abs(f - want[k]) < best_error) best_error = std::abs(f - want[k]), best = joint;
        }
        if (best >= 0 && has_target(names[k])) {
          map[names[k]] = bvh.joints[best].name;
          last = fraction(best);
        }
      }
    }
  }
  return map;
}

BvhRetargetResult RetargetBvh(const BvhMotion& motion, const Skeleton& target, const BvhRetargetOptions& options,
                              const std::string& source) {
  options.Check();
  const Skeleton& bvh = motion.skeleton;
  if (motion.frames.empty()) throw InputError(source, "the BVH has no motion frames");
  std::vector<std::string> target_names;
  for (const Joint& joint : target.joints) target_names.push_back(joint.name);
  for (const char* name : {"pelvis", "left_hip", "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle"})
    if (target.IndexOf(name) < 0)
      throw UsageError(std::string("bvh retargeting: the target skeleton has no joint '") + name + "'");
  if (target.joints[0].name != "pelvis") throw UsageError("bvh retargeting: the target skeleton's root must be 'pelvis'");

  BvhRetargetResult result;
  result.fps = motion.frame_time_s > 0 ? 1.0 / motion.frame_time_s : 30.0;
  if (!(motion.frame_time_s > 0)) result.warnings.push_back("Frame Time is not positive; assuming 30 fps");
  auto with_overrides = [&](std::map<std::string, std::string> map) {
    for (const auto& [target_name, bvh_name] : options.joint_map) {
      if (target.IndexOf(target_name) < 0)
        throw UsageError("bvh joint map: the target skeleton has no joint '" + target_name + "'");
      if (bvh_name.empty()) {
        map.erase(target_name);
      } else {
        if (bvh.IndexOf(bvh_name) < 0)
          throw InputError(source, "the joint map names '" + bvh_name + "' (for " + target_name +
                                       "), which the BVH does not have");
        map[target_name] = bvh_name;
      }
    }
    return map;
  };
  result.joint_map = with_overrides(GuessBvhJointMap(bvh, target_names));
  std::vector<std::string> missing;
  for (const std::string& name : EssentialJoints())
    if (target.IndexOf(name) >= 0 && !result.joint_map.count(name)) missing.push_back(name);
  if (!result.joint_map.count("neck") && !result.joint_map.count("head")) missing.push_back("head or neck");
  if (!missing.empty()) {
    std::string list, joints;
    for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
    for (int j = 0; j < bvh.size() && j < 40; ++j) joints += (j ? " " : "") + bvh.joints[j].name;
    if (bvh.size() > 40) joints += " ...";
    throw InputError(source, "cannot map the essential target joints " + list + " to the BVH skeleton (joints: " +
                                 joints + "); name them with a joint map, e.g. --bvh-map left_shoulder=LeftArm");
  }
  // The pose that defines axes and alignment (the rest pose, or a standing frame); when it is a
  // frame, the spine and chest are picked again by their heights in it.
  auto bvh_joint = [&](const char* name) { return bvh.IndexOf(result.joint_map.at(name)); };
  const int top = bvh_joint(result.joint_map.count("head") ? "head" : "neck");
  const int hips[2] = {bvh_joint("left_hip"), bvh_joint("right_hip")};
  const int ankles[2] = {bvh_joint("left_ankle"), bvh_joint("right_ankle")};
  const std::vector<Eigen::Isometry3d> reference =
      ReferencePose(motion, bvh_joint("pelvis"), top, hips, ankles, &result.reference_frame);
  std::vector<Vector3d> bvh_rest(reference.size());  // joint positions in the reference pose
  for (std::size_t j = 0; j < reference.size(); ++j) bvh_rest[j] = reference[j].translation();
  if (result.reference_frame >= 0) {
    result.joint_map = with_overrides(GuessBvhJointMap(bvh, target_names, bvh_rest));
    result.warnings.push_back("the BVH's rest pose is not a standing body; frame " +
                              std::to_string(result.reference_frame) + " defines its axes and bone alignment");
  }
  const int nt = target.size();
  std::vector<int> map_index(nt, -1);  // target joint -> BVH joint
  for (int j = 0; j < nt; ++j) {
    const auto it = result.joint_map.find(target.joints[j].name);
    if (it != result.joint_map.end()) map_index[j] = bvh.IndexOf(it->second);
    else result.unmapped.push_back(target.joints[j].name);
  }
  auto bvh_of = [&](const char* name) { return map_index[target.IndexOf(name)]; };

  // Axes, units and sizes from the BVH's reference pose (raw file axes and units).
  const std::vector<Vector3d> target_rest = target.RestPositions();
  Vector3d up = Vector3d::UnitY();
  if (options.up_axis == 'z') {
    up = Vector3d::UnitZ();
  } else if (options.up_axis == 'a') {
    const Vector3d v = bvh_rest[top] - 0.5 * (bvh_rest[ankles[0]] + bvh_rest[ankles[1]]);
    int axis = 0;
    v.cwiseAbs().maxCoeff(&axis);
    up = Vector3d::Unit(axis) * (v(axis) < 0 ? -1.0 : 1.0);
  }
  result.up_axis = up.y() != 0 ? 'y' : up.z() != 0 ? 'z' : 'x';
  if (up.sum() < 0) result.warnings.push_back("the BVH's up axis points along -" + std::string(1, result.up_axis));
  const Matrix3d z_from_raw = Quaterniond::FromTwoVectors(up, Vector3d::UnitZ()).toRotationMatrix();
  double lo = std::numeric_limits<double>::max(), hi = -lo;
  for (const Vector3d& p : bvh_rest) lo = std::min(lo, p.dot(up)), hi = std::max(hi, p.dot(up));
  result.bvh_height = hi - lo;
  const UnitGuess units[] = {{"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}, {"inch", 0.0254}, {"cmu", 0.0254 / 0.45}};
  double best = std::numeric_limits<double>::max();
  for (const UnitGuess& unit : units) {
    const double error = std::abs(std::log(std::max(result.bvh_height, 1e-12) * unit.metres / 1.7));
    if (error < best) best = error, result.unit = unit.name, result.metres_per_unit = unit.metres;
  }
  auto leg = [](const std::vector<Vector3d>& rest, int hip, int knee, int ankle) {
    return (rest[knee] - rest[hip]).norm() + (rest[ankle] - rest[knee]).norm();
  };
  const double bvh_leg = 0.5 * (leg(bvh_rest, bvh_of("left_hip"), bvh_of("left_knee"), bvh_of("left_ankle")) +
                                leg(bvh_rest, bvh_of("right_hip"), bvh_of("right_knee"), bvh_of("right_ankle")));
  const double target_leg =
      0.5 * (leg(target_rest, target.IndexOf("left_hip"), target.IndexOf("left_knee"), target.IndexOf("left_ankle")) +
             leg(target_rest, target.IndexOf("right_hip"), target.IndexOf("right_knee"), target.IndexOf("right_ankle")));
  if (!(bvh_leg > 0)) throw InputError(source, "the BVH's legs have zero length at rest");
  result.translation_scale = target_leg / bvh_leg;

  // Heading: frame 0's (left hip - right hip) x up onto the target's rest one.
  const auto frame0 = JointPositions(bvh, motion.frames[0]);
  Matrix3d yaw = Matrix3d::Identity();
  if (options.face_target) {
    const Vector3d lr = z_from_raw * (frame0[bvh_of("left_hip")] - frame0[bvh_of("right_hip")]);
    const Vector3d lr_t = target_rest[target.IndexOf("left_hip")] - target_rest[target.IndexOf("right_hip")];
    Vector3d f = lr.cross(Vector3d::UnitZ()), f_t = lr_t.cross(Vector3d::UnitZ());
    f.z() = f_t.z() = 0;
    if (f.norm() > 1e-9 && f_t.norm() > 1e-9)
      yaw = Eigen::AngleAxisd(std::atan2(f.normalized().cross(f_t.normalized()).z(), f.normalized().dot(f_t.normalized())),
                              Vector3d::UnitZ()).toRotationMatrix();
  }
  const Matrix3d m = yaw * z_from_raw;
  result.world_from_bvh = m;

  // Alignment per mapped target joint, in the mapped BVH joint's frame: its reference rotation
  // undone after turning the target's rest child directions onto the BVH's reference ones. The
  // child directions are kept in the BVH joint's frame too (`local_child`).
  std::vector<std::vector<int>> children(nt);
  for (int j = 1; j < nt; ++j) children[target.joints[j].parent].push_back(j);
  const double tiny = 1e-6 * std::max(result.bvh_height, 1e-12);
  std::vector<Matrix3d> align(nt, Matrix3d::Identity());
  std::vector<Matrix3d> reference_world(nt, Matrix3d::Identity());  // target joints in the reference pose
  // The BVH joint that gives a mapped child's direction: the child itself, or, when it lies on
  // its parent (CMU's LeftFingerBase, an offset of zero), its first descendant that does not.
  std::vector<int> bvh_first_child(bvh.size(), -1);
  for (int c = bvh.size() - 1; c > 0; --c)
    if (bvh.joints[c].parent >= 0) bvh_first_child[bvh.joints[c].parent] = c;
  auto direction_joint = [&](int b, int c) {
    while (c >= 0 && (bvh_rest[c] - bvh_rest[b]).norm() < tiny) c = bvh_first_child[c];
    return c;
  };
  std::vector<std::vector<int>> used_children(nt);  // BVH joints giving each target joint's child directions
  std::vector<std::vector<Vector3d>> local_child(nt);
  for (int j = 0; j < nt; ++j) {
    const int b = map_index[j];
    const int parent = target.joints[j].parent;
    if (j > 0) reference_world[j] = reference_world[parent];
    if (b < 0) continue;
    const Matrix3d reference_rotation = m * reference[b].linear() * m.transpose();
    std::vector<Vector3d> from, to;
    for (int c : children[j]) {
      if (map_index[c] < 0) continue;
      const int d_joint = direction_joint(b, map_index[c]);
      if (d_joint < 0) continue;
      const Vector3d d = m * (bvh_rest[d_joint] - bvh_rest[b]);
      const Vector3d t = target_rest[c] - target_rest[j];
      if (t.norm() < 1e-9) continue;
      from.push_back(t.normalized());
      to.push_back(d.normalized());
      used_children[j].push_back(d_joint);
      local_child[j].push_back(reference_rotation.transpose() * d);
    }
    // A mapped joint without a mapped child (a head over a neck that leans, as CMU's ASF necks
    // do; a spine below an unmapped chest) takes the pelvis's orientation in the reference pose
    // (the body's heading), rather than its parent's tilt; a limb's (a wrist over an End Site of
    // length zero, as in Bandai Namco's files) its parent's, so that the hand continues the
    // forearm as at the target's rest (with the pelvis's, the hands came out bent by the angle
    // between the two rest poses' arms, 50 degrees and more). A joint with one child keeps its
    // parent's twist: turned only as far as its bone needs (CMU's subject 94 stands at rest
    // facing away from its first frame; without the parent's twist every single-child joint
    // came out turned half round about its bone against its parent: a spine twisted by 180
    // degrees, the head facing backwards).
    const std::string& name = target.joints[j].name;
    const bool limb = name.rfind("left_", 0) == 0 || name.rfind("right_", 0) == 0;
    if (from.empty()) reference_world[j] = limb && parent >= 0 ? reference_world[parent] : reference_world[0];
    else reference_world[j] = BestRotation(from, to, reference_world[j]);
    align[j] = reference_rotation.transpose() * reference_world[j];
  }

  // Per frame: world rotations of the target joints, then local rotations and the root.
  const int pelvis_bvh = map_index[0];
  std::vector<Vector3d> pelvis_at(motion.frames.size());
  std::vector<Matrix3d> world(nt);
  // Run again after the elbow hinges below turn an arm's alignment.
  auto retarget_frames = [&]() {
    result.poses.clear();
    result.poses.reserve(motion.frames.size());
    for (std::size_t f = 0; f < motion.frames.size(); ++f) {
      const std::vector<Eigen::Isometry3d> bvh_world = WorldFromJoint(bvh, motion.frames[f]);
      Pose pose = Pose::Rest(nt);
      for (int j = 0; j < nt; ++j) {
        const int b = map_index[j];
        const int parent = target.joints[j].parent;
        if (b < 0) {
          world[j] = parent >= 0 ? world[parent] : Matrix3d::Identity();
        } else {
          const Matrix3d g = m * bvh_world[b].linear() * m.transpose();
          std::vector<Vector3d> predicted, actual;
          for (std::size_t k = 0; k < used_children[j].size(); ++k) {
            const int c = used_children[j][k];
            const Vector3d a = m * (bvh_world[c].translation() - bvh_world[b].translation());
            if (a.norm() < tiny) continue;
            predicted.push_back((g * local_child[j][k]).normalized());
            actual.push_back(a.normalized());
          }
          world[j] = BestRotation(predicted, actual) * g * align[j];
        }
        const Matrix3d local = parent >= 0 ? Matrix3d(world[parent].transpose() * world[j]) : world[j];
        pose.local_rotations[j] = Quaterniond(local).normalized();
      }
      pelvis_at[f] = result.translation_scale * (m * bvh_world[pelvis_bvh].translation());
      result.poses.push_back(std::move(pose));
    }
  };
  retarget_frames();

  // Elbow hinges. The arms are aligned at rest by the shortest turn of each bone, which leaves
  // the BVH arm's twist as its rest pose had it: its elbow then bends about another axis than the
  // target's (Bandai Namco's punch: 25-38 degrees off, a forearm swung sideways out of the
  // target's flexion plane). Each arm is turned about its own bones so that the elbow's mean
  // flexion axis over the motion lands on the target's hinge, and the motion retargeted again.
  const Vector3d lateral = target_rest[target.IndexOf("left_hip")] - target_rest[target.IndexOf("right_hip")];
  bool turned = false;
  for (const char* side : {"left", "right"}) {
    const int shoulder = target.IndexOf(std::string(side) + "_shoulder");
    const int elbow = target.IndexOf(std::string(side) + "_elbow");
    const int wrist = target.IndexOf(std::string(side) + "_wrist");
    const Vector3d upper = (target_rest[elbow] - target_rest[shoulder]).normalized();
    const double turn = ElbowHingeTurn(result.poses, elbow, upper, lateral);
    if (std::abs(turn) < options.min_hinge_turn_rad) continue;
    result.elbow_turns_deg[side] = turn * 180.0 / M_PI;
    align[shoulder] = align[shoulder] * Eigen::AngleAxisd(turn, upper).toRotationMatrix();
    const Vector3d fore = (target_rest[wrist] - target_rest[elbow]).normalized();
    const Matrix3d fore_turn = Eigen::AngleAxisd(turn, fore).toRotationMatrix();
    align[elbow] = align[elbow] * fore_turn;
    align[wrist] = align[wrist] * fore_turn;
    turned = true;
  }
  if (turned) retarget_frames();

  // A pelvis faster than any performer (10 m/s) is a jump in the recording, often a reference
  // pose in the first frames.
  for (std::size_t f = 1; f < pelvis_at.size(); ++f)
    if ((pelvis_at[f] - pelvis_at[f - 1]).norm() * result.fps > 10.0) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "the pelvis jumps %.2f m between frames %zu and %zu (%.2f s): start after it (e.g. --bvh-start)",
                    (pelvis_at[f] - pelvis_at[f - 1]).norm(), f - 1, f, f / result.fps);
      result.warnings.push_back(text);
      break;
    }

  // Root placement: scaled BVH pelvis path, centred and put on the floor.
  Vector3d shift = Vector3d::Zero();
  if (options.center_on_target) shift.head<2>() = target_rest[0].head<2>() - pelvis_at[0].head<2>();
  for (std::size_t f = 0; f < result.poses.size(); ++f)
    result.poses[f].root_translation = pelvis_at[f] + shift - target.joints[0].offset_in_parent;
  if (options.feet_on_floor) {
    std::vector<int> feet;
    for (const char* name : {"left_ankle", "right_ankle", "left_toe", "right_toe"})
      if (target.IndexOf(name) >= 0) feet.push_back(target.IndexOf(name));
    double rest_low = std::numeric_limits<double>::max(), low = rest_low;
    for (int j : feet) rest_low = std::min(rest_low, target_rest[j].z());
    for (const Pose& pose : result.poses) {
      const std::vector<Vector3d> positions = JointPositions(target, pose);
      for (int j : feet) low = std::min(low, positions[j].z());
    }
    for (Pose& pose : result.poses) pose.root_translation.z() += rest_low - low;
  }
  for (const std::string& warning : motion.warnings) result.warnings.push_back(warning);
  return result;
}

BvhRetargetResult RetargetBvhFile(const std::string& path, const Skeleton& target, const BvhRetargetOptions& options) {
  return RetargetBvh(ReadBvh(path), target, options, path);
}

Pose SamplePoses(const std::vector<Pose>& poses, double source_fps, double time_s) {
  const double u = std::clamp(time_s * source_fps, 0.0, static_cast<double>(poses.size() - 1));
  const std::size_t i = std::min(static_cast<std::size_t>(u), poses.size() - 1);
  const std::size_t k = std::min(i + 1, poses.size() - 1);
  const double t = u - static_cast<double>(i);
  Pose pose = poses[i];
  pose.root_translation = (1 - t) * poses[i].root_translation + t * poses[k].root_translation;
  for (std::size_t j = 0; j < pose.local_rotations.size() && j < poses[k].local_rotations.size(); ++j)
    pose.local_rotations[j] = poses[i].local_rotations[j].slerp(t, poses[k].local_rotations[j]);
  return pose;
}

std::vector<Pose> SampleRetargetedMotion(const BvhRetargetResult& motion, double fps, double speed, int max_frames,
                                         double start_s) {
  if (!(fps > 0) || !(speed > 0)) throw UsageError("bvh sampling: fps and speed must be positive");
  std::vector<Pose> poses;
  if (motion.poses.empty()) return poses;
  const double duration_s = (motion.poses.size() - 1) / motion.fps;
  if (!(start_s >= 0) || start_s > duration_s)
    throw UsageError("bvh sampling: the start " + std::to_string(start_s) + " s is outside the motion (0 to " +
                     std::to_string(duration_s) + " s)");
  for (int f = 0; f < max_frames; ++f) {
    const double t = start_s + f / fps * speed;
    if (t > duration_s + 1e-9) break;
    poses.push_back(SamplePoses(motion.poses, motion.fps, t));
  }
  return poses;
}

std::map<std::string, std::string> ParseBvhJointMap(const std::string& text, const std::string& flag) {
  std::map<std::string, std::string> map;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, end - start);
    start = end + 1;
    if (item.empty()) continue;
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0)
      throw UsageError(flag + ": expected target=bvh_joint items separated by commas, got '" + item + "'");
    map[item.substr(0, eq)] = item.substr(eq + 1);
  }
  return map;
}

}  // namespace confluent
