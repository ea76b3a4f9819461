// BVH retargeting: name mapping, bone directions and twist against a synthetic BVH with known
// rotations, root scaling, units and axes, and clear errors for bad files.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include "core/bvh_io.h"
#include "core/bvh_retarget.h"
#include "core/error.h"
#include "tests/support/bvh_fixture.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using namespace testing::bvh_fixture;  // NOLINT

using Eigen::Matrix3d;
using Eigen::Vector3d;

// A 22-joint skeleton with the studio joint names in an A-pose facing +y (Z up, metres).
Skeleton StudioLikeSkeleton() {
  const std::vector<std::pair<std::string, int>> joints = {
      {"pelvis", -1},        {"spine", 0},         {"chest", 1},           {"neck", 2},           {"head", 3},
      {"head_end", 4},       {"left_shoulder", 2}, {"left_elbow", 6},      {"left_wrist", 7},     {"left_hand_end", 8},
      {"right_shoulder", 2}, {"right_elbow", 10},  {"right_wrist", 11},    {"right_hand_end", 12}, {"left_hip", 0},
      {"left_knee", 14},     {"left_ankle", 15},   {"left_toe", 16},       {"right_hip", 0},      {"right_knee", 18},
      {"right_ankle", 19},   {"right_toe", 20}};
  std::vector<Vector3d> rest(joints.size());
  rest[0] = {0, 0, 0.96};
  rest[1] = {0, -0.005, 1.10};
  rest[2] = {0, -0.01, 1.28};
  rest[3] = {0, -0.012, 1.455};
  rest[4] = {0, -0.005, 1.56};
  rest[5] = {0, 0.005, 1.75};
  for (int side = 0; side < 2; ++side) {
    const double sx = side == 0 ? -1 : 1;
    const Vector3d dir(sx * std::sin(0.7), 0, -std::cos(0.7));
    const int s = side == 0 ? 6 : 10, h = side == 0 ? 14 : 18;
    rest[s] = {sx * 0.19, -0.015, 1.425};
    rest[s + 1] = rest[s] + 0.285 * dir;
    rest[s + 2] = rest[s + 1] + 0.25 * dir;
    rest[s + 3] = rest[s + 2] + 0.18 * dir;
    rest[h] = {sx * 0.09, 0, 0.91};
    rest[h + 1] = {sx * 0.102, 0.005, 0.49};
    rest[h + 2] = {sx * 0.112, -0.02, 0.085};
    rest[h + 3] = {sx * 0.125, 0.15, 0.02};
  }
  Skeleton skeleton;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const int parent = joints[j].second;
    skeleton.joints.push_back({joints[j].first, parent, parent < 0 ? rest[j] : Vector3d(rest[j] - rest[parent])});
  }
  return skeleton;
}

// Bones whose parent joint has a single child in the target: their direction must be exact.
const std::vector<std::pair<std::string, std::string>> kSingleChildBones = {
    {"spine", "chest"},          {"neck", "head"},          {"head", "head_end"},
    {"left_shoulder", "left_elbow"}, {"left_elbow", "left_wrist"}, {"left_wrist", "left_hand_end"},
    {"right_shoulder", "right_elbow"}, {"right_elbow", "right_wrist"}, {"right_wrist", "right_hand_end"},
    {"left_hip", "left_knee"},   {"left_knee", "left_ankle"}, {"left_ankle", "left_toe"},
    {"right_hip", "right_knee"}, {"right_knee", "right_ankle"}, {"right_ankle", "right_toe"}};

// Every bone of kSingleChildBones points where its mapped BVH bone points, in every frame (cosine
// of the angle between them above 1 - tolerance); `check` (may be empty) sees each bone's joints'
// world transforms too: check(frame, from, target joint a, BVH joint ba, target transforms, BVH transforms).
using BoneCheck = std::function<void(std::size_t, const std::string&, int, int, const std::vector<Eigen::Isometry3d>&,
                                     const std::vector<Eigen::Isometry3d>&)>;
void ExpectBonesPointAsInTheBvh(const BvhMotion& motion, const Skeleton& target, const BvhRetargetResult& result,
                                double tolerance, const BoneCheck& check = {}) {
  const Matrix3d m = result.world_from_bvh;
  for (std::size_t f = 0; f < motion.frames.size(); ++f) {
    const std::vector<Eigen::Isometry3d> bvh = WorldFromJoint(motion.skeleton, motion.frames[f]);
    const std::vector<Eigen::Isometry3d> tgt = WorldFromJoint(target, result.poses[f]);
    for (const auto& [from, to] : kSingleChildBones) {
      const int a = target.IndexOf(from), b = target.IndexOf(to);
      const int ba = motion.skeleton.IndexOf(result.joint_map.at(from));
      const int bb = motion.skeleton.IndexOf(result.joint_map.at(to));
      const Vector3d want = (m * (bvh[bb].translation() - bvh[ba].translation())).normalized();
      const Vector3d got = (tgt[b].translation() - tgt[a].translation()).normalized();
      EXPECT_GT(want.dot(got), 1 - tolerance) << "frame " << f << " bone " << from << " -> " << to;
      if (check) check(f, from, a, ba, tgt, bvh);
    }
  }
}

TEST(BvhRetarget, MapsCmuNamesAndDetectsAxesAndUnits) {
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(TestFrames());
  const BvhRetargetResult result = RetargetBvhFile(dir / "m.bvh", StudioLikeSkeleton());
  const std::map<std::string, std::string> expected = {
      {"pelvis", "Hips"},           {"spine", "Spine"},          {"chest", "Spine1"},
      {"neck", "Neck"},             {"head", "Head"},            {"head_end", "Head_end"},
      {"left_shoulder", "LeftArm"}, {"left_elbow", "LeftForeArm"}, {"left_wrist", "LeftHand"},
      {"left_hand_end", "LeftHand_end"}, {"left_hip", "LeftUpLeg"}, {"left_knee", "LeftLeg"},
      {"left_ankle", "LeftFoot"},   {"left_toe", "LeftToeBase"}, {"right_toe", "RightToeBase"},
      {"right_shoulder", "RightArm"}, {"right_hand_end", "RightHand_end"}};
  for (const auto& [target, bvh] : expected) {
    ASSERT_TRUE(result.joint_map.count(target)) << target;
    EXPECT_EQ(result.joint_map.at(target), bvh) << target;
  }
  EXPECT_TRUE(result.unmapped.empty());
  EXPECT_EQ(result.up_axis, 'y');
  EXPECT_EQ(result.unit, "cm");
  EXPECT_NEAR(result.bvh_height, 168.0 - 1.0, 1e-9);
  EXPECT_NEAR(result.fps, 50.0, 1e-9);
  ASSERT_EQ(result.poses.size(), 3u);
  // Y up -> Z up; the BVH faces +z (-> -y after the axis change), the target +y: a half turn.
  const Matrix3d expected_m = Eigen::AngleAxisd(M_PI, Vector3d::UnitZ()).toRotationMatrix() *
                              Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitX()).toRotationMatrix();
  EXPECT_LT((result.world_from_bvh - expected_m).norm(), 1e-9);
}

TEST(BvhRetarget, BonesPointWhereTheBvhBonesPointWithTheirTwist) {
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(TestFrames());
  const BvhMotion motion = ReadBvh(dir / "m.bvh");
  const Skeleton target = StudioLikeSkeleton();
  const BvhRetargetResult result = RetargetBvh(motion, target, {}, dir / "m.bvh");
  const Matrix3d m = result.world_from_bvh;
  const std::vector<Eigen::Isometry3d> target_rest = WorldFromJoint(target, result.poses[0]);
  const std::vector<Eigen::Isometry3d> bvh_rest = WorldFromJoint(motion.skeleton, motion.frames[0]);
  // Twist too: the bone's change of orientation since frame 0 equals the BVH joint's.
  ExpectBonesPointAsInTheBvh(motion, target, result, 1e-10,
                             [&](std::size_t f, const std::string& from, int a, int ba,
                                 const std::vector<Eigen::Isometry3d>& tgt, const std::vector<Eigen::Isometry3d>& bvh) {
                               const Matrix3d bvh_change =
                                   m * bvh[ba].linear() * bvh_rest[ba].linear().transpose() * m.transpose();
                               const Matrix3d target_change = tgt[a].linear() * target_rest[a].linear().transpose();
                               EXPECT_LT((bvh_change - target_change).norm(), 1e-9) << "frame " << f << " joint " << from;
                             });
  // Frame 2 twists the left forearm by 40 degrees about its own axis: the target elbow turns by
  // 40 degrees about its bone relative to the upper arm.
  const std::vector<Eigen::Isometry3d> t1 = WorldFromJoint(target, result.poses[2]);
  const int elbow = target.IndexOf("left_elbow"), shoulder = target.IndexOf("left_shoulder");
  const Eigen::AngleAxisd twist(Matrix3d(t1[shoulder].linear().transpose() * t1[elbow].linear()));
  EXPECT_NEAR(twist.angle(), 40 * M_PI / 180, 1e-9);
  // The root moves as the BVH root, scaled by the leg-length ratio (target 0.83 m / 84 cm).
  const double scale = result.translation_scale;
  const double target_leg = (Vector3d(0.102, 0.005, 0.49) - Vector3d(0.09, 0, 0.91)).norm() +
                            (Vector3d(0.112, -0.02, 0.085) - Vector3d(0.102, 0.005, 0.49)).norm();
  EXPECT_NEAR(scale, target_leg / 84.0, 1e-12);
  const Vector3d moved = result.poses[1].root_translation - result.poses[0].root_translation;
  EXPECT_LT((moved - scale * (m * Vector3d(10, 0, 0))).norm(), 1e-12);
  // Frame 0 is centred above the target pelvis; the lowest foot joint over all frames is on the
  // target's rest foot height.
  EXPECT_LT(result.poses[0].root_translation.head<2>().norm(), 1e-12);
  double low = 1e9;
  for (const Pose& pose : result.poses) {
    const auto p = JointPositions(target, pose);
    for (const char* name : {"left_ankle", "right_ankle", "left_toe", "right_toe"}) low = std::min(low, p[target.IndexOf(name)].z());
  }
  EXPECT_NEAR(low, 0.02, 1e-12);
}

// A hand whose End Site lies on the wrist (Bandai Namco's files) gives no direction: the target's
// hand continues its forearm, turned only by the BVH's wrist rotation. (It kept the pelvis's
// orientation of the BVH's T-pose: bent by the 50 degrees between the T- and the A-pose arm.)
TEST(BvhRetarget, HandWithoutADirectionContinuesTheForearm) {
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(TestFrames(), {}, 0.0);
  const BvhMotion motion = ReadBvh(dir / "m.bvh");
  const Skeleton target = StudioLikeSkeleton();
  const BvhRetargetResult result = RetargetBvh(motion, target, {}, dir / "m.bvh");
  for (std::size_t f = 0; f < result.poses.size(); ++f) {
    const auto p = JointPositions(target, result.poses[f]);
    for (const char* side : {"left", "right"}) {
      const std::string s(side);
      const Vector3d forearm = p[target.IndexOf(s + "_wrist")] - p[target.IndexOf(s + "_elbow")];
      const Vector3d hand = p[target.IndexOf(s + "_hand_end")] - p[target.IndexOf(s + "_wrist")];
      EXPECT_GT(forearm.normalized().dot(hand.normalized()), 1 - 1e-9) << "frame " << f << " " << side;
    }
  }
  // A wrist rotation of the BVH bends the hand by as much.
  std::ofstream(dir / "bent.bvh") << SyntheticBvh({Frame({0, 0, 0}, {}), Frame({0, 0, 0}, {{kLHand, {30, 0, 0}}})}, {}, 0.0);
  const BvhMotion bent_motion = ReadBvh(dir / "bent.bvh");
  const BvhRetargetResult bent = RetargetBvh(bent_motion, target, {}, dir / "bent.bvh");
  const auto p = JointPositions(target, bent.poses[1]);
  const Vector3d forearm = p[target.IndexOf("left_wrist")] - p[target.IndexOf("left_elbow")];
  const Vector3d hand = p[target.IndexOf("left_hand_end")] - p[target.IndexOf("left_wrist")];
  EXPECT_NEAR(std::acos(forearm.normalized().dot(hand.normalized())), 30 * M_PI / 180, 1e-6);
}

TEST(BvhRetarget, SamplePosesInterpolates) {
  Pose a = Pose::Rest(2), b = Pose::Rest(2);
  b.root_translation = Vector3d(1, 2, 3);
  b.local_rotations[1] = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Vector3d::UnitZ()));
  const Pose mid = SamplePoses({a, b}, 10.0, 0.025);  // a quarter of the way
  EXPECT_LT((mid.root_translation - Vector3d(0.25, 0.5, 0.75)).norm(), 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(mid.local_rotations[1]).angle(), 0.25, 1e-12);
  EXPECT_LT((SamplePoses({a, b}, 10.0, 5.0).root_translation - b.root_translation).norm(), 1e-12);
  EXPECT_EQ(ParseBvhJointMap("left_hip=LThigh,spine=").at("spine"), "");
  EXPECT_THROW(ParseBvhJointMap("left_hip"), UsageError);
}

TEST(BvhRetarget, BadFilesGiveClearErrors) {
  testing::TempDir dir;
  const Skeleton target = StudioLikeSkeleton();
  // Truncated: the motion block stops early.
  std::string text = SyntheticBvh(TestFrames());
  std::ofstream(dir / "truncated.bvh") << text.substr(0, text.size() - 40);
  try {
    RetargetBvhFile(dir / "truncated.bvh", target);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("truncated.bvh"), std::string::npos) << e.what();
  }
  // An unknown channel.
  std::string bad = text;
  bad.replace(bad.find("Xrotation"), 9, "Wrotation");
  std::ofstream(dir / "channel.bvh") << bad;
  try {
    RetargetBvhFile(dir / "channel.bvh", target);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("channel.bvh"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Wrotation"), std::string::npos) << e.what();
  }
  // Arms with names no table knows: the error names the file and the joints; a joint map fixes it.
  const std::map<std::string, std::string> rename = {{"LeftArm", "bone7"}, {"LeftForeArm", "bone8"},
                                                     {"LeftHand", "bone9"}};
  std::ofstream(dir / "odd.bvh") << SyntheticBvh(TestFrames(), rename);
  try {
    RetargetBvhFile(dir / "odd.bvh", target);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("odd.bvh"), std::string::npos) << what;
    EXPECT_NE(what.find("left_shoulder, left_elbow, left_wrist"), std::string::npos) << what;
    EXPECT_NE(what.find("bone7"), std::string::npos) << what;
  }
  BvhRetargetOptions options;
  options.joint_map = {{"left_shoulder", "bone7"}, {"left_elbow", "bone8"}, {"left_wrist", "bone9"}};
  EXPECT_EQ(RetargetBvhFile(dir / "odd.bvh", target, options).joint_map.at("left_elbow"), "bone8");
  options.joint_map["left_wrist"] = "nosuchjoint";
  EXPECT_THROW(RetargetBvhFile(dir / "odd.bvh", target, options), InputError);
}

// The same motion re-expressed over a rest pose that is no standing body: every joint's frame
// turned so that its first child's offset lies along +x, as in Bandai Namco's files, the frames'
// rotations compensating (r'_j = C_parent^T r_j C_j), so every joint stays where it was.
BvhMotion WithRestAlongX(const BvhMotion& motion) {
  const int n = motion.skeleton.size();
  std::vector<Matrix3d> turn(n, Matrix3d::Identity());
  for (int j = 0; j < n; ++j)
    for (int c = j + 1; c < n; ++c)
      if (motion.skeleton.joints[c].parent == j) {
        const Vector3d offset = motion.skeleton.joints[c].offset_in_parent;
        if (offset.norm() > 0) turn[j] = Eigen::Quaterniond::FromTwoVectors(Vector3d::UnitX(), offset).toRotationMatrix();
        break;
      }
  BvhMotion out = motion;
  for (int j = 1; j < n; ++j) {
    const int parent = motion.skeleton.joints[j].parent;
    out.skeleton.joints[j].offset_in_parent = turn[parent].transpose() * motion.skeleton.joints[j].offset_in_parent;
  }
  for (std::size_t f = 0; f < motion.frames.size(); ++f)
    for (int j = 0; j < n; ++j) {
      const int parent = motion.skeleton.joints[j].parent;
      const Matrix3d before = parent < 0 ? Matrix3d(Matrix3d::Identity()) : Matrix3d(turn[parent].transpose());
      out.frames[f].local_rotations[j] =
          Eigen::Quaterniond(before * motion.frames[f].local_rotations[j].toRotationMatrix() * turn[j]).normalized();
    }
  return out;
}

TEST(BvhRetarget, RestPoseThatIsNoStandingBodyGivesTheSameBody) {
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(TestFrames());
  const BvhMotion motion = ReadBvh(dir / "m.bvh");
  const BvhMotion along_x = WithRestAlongX(motion);
  // The re-expression keeps every joint where it was, and its rest pose is a line along +x.
  for (std::size_t f = 0; f < motion.frames.size(); ++f) {
    const auto a = JointPositions(motion.skeleton, motion.frames[f]), b = JointPositions(along_x.skeleton, along_x.frames[f]);
    for (int j = 0; j < motion.skeleton.size(); ++j) ASSERT_LT((a[j] - b[j]).norm(), 1e-9);
  }
  const auto line = along_x.skeleton.RestPositions();
  EXPECT_GT((line[along_x.skeleton.IndexOf("Head")] - line[0]).x(), 0);
  EXPECT_GT((line[along_x.skeleton.IndexOf("LeftFoot")] - line[0]).x(), 0);

  const Skeleton target = StudioLikeSkeleton();
  const BvhRetargetResult expected = RetargetBvh(motion, target);
  const BvhRetargetResult result = RetargetBvh(along_x, target);
  EXPECT_EQ(expected.reference_frame, -1);
  EXPECT_EQ(result.reference_frame, 0);  // frame 0 is the T-pose
  EXPECT_EQ(result.up_axis, 'y');
  EXPECT_EQ(result.unit, expected.unit);
  EXPECT_NEAR(result.translation_scale, expected.translation_scale, 1e-12);
  ASSERT_EQ(result.poses.size(), expected.poses.size());
  for (std::size_t f = 0; f < result.poses.size(); ++f) {
    const auto want = WorldFromJoint(target, expected.poses[f]), got = WorldFromJoint(target, result.poses[f]);
    for (int j = 0; j < target.size(); ++j) {
      EXPECT_LT((want[j].translation() - got[j].translation()).norm(), 1e-9) << "frame " << f << " joint " << j;
      EXPECT_LT((want[j].linear() - got[j].linear()).norm(), 1e-9) << "frame " << f << " joint " << j;
    }
  }
}

// A performer who faces away from the BVH's rest pose in every frame (CMU's subject 94: the rest
// pose faces +z, the dance -z). Turned to face the target at frame 0, the body is the same as
// that of the same motion performed facing the rest pose's way: no bone turned half round about
// itself against its parent (before, the spine and the neck were, and the head faced backwards).
TEST(BvhRetarget, PerformerFacingAwayFromTheRestPoseGivesTheSameBody) {
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(TestFrames());
  const BvhMotion motion = ReadBvh(dir / "m.bvh");
  BvhMotion away = motion;
  const Eigen::Quaterniond half_turn(Eigen::AngleAxisd(M_PI, Vector3d::UnitY()));  // about the BVH's up
  for (Pose& frame : away.frames) {
    frame.root_translation = half_turn * frame.root_translation;
    frame.local_rotations[0] = half_turn * frame.local_rotations[0];
  }
  const Skeleton target = StudioLikeSkeleton();
  const BvhRetargetResult expected = RetargetBvh(motion, target);
  const BvhRetargetResult result = RetargetBvh(away, target);
  ASSERT_EQ(result.poses.size(), expected.poses.size());
  for (std::size_t f = 0; f < result.poses.size(); ++f) {
    const auto want = WorldFromJoint(target, expected.poses[f]), got = WorldFromJoint(target, result.poses[f]);
    for (int j = 0; j < target.size(); ++j) {
      EXPECT_LT((want[j].translation() - got[j].translation()).norm(), 1e-9) << "frame " << f << " " << target.joints[j].name;
      EXPECT_LT((want[j].linear() - got[j].linear()).norm(), 1e-9) << "frame " << f << " " << target.joints[j].name;
    }
  }
  // And at frame 0 (a T-pose) no joint is turned against its parent by more than the bones'
  // rest directions ask (the arms: 50 degrees up from the target's A-pose).
  for (int j = 1; j < target.size(); ++j)
    EXPECT_LT(Eigen::AngleAxisd(result.poses[0].local_rotations[j]).angle(), 55 * M_PI / 180) << target.joints[j].name;
}

// CMU's ASF exports have no head joint: LowerNeck -> Neck, where the upper neck turns the head.
TEST(BvhRetarget, UpperOfTwoNeckJointsTurnsTheHead) {
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(TestFrames(), {{"Neck", "LowerNeck"}, {"Head", "Neck"}});
  const BvhRetargetResult result = RetargetBvhFile(dir / "m.bvh", StudioLikeSkeleton());
  EXPECT_EQ(result.joint_map.at("neck"), "LowerNeck");
  EXPECT_EQ(result.joint_map.at("head"), "Neck");
  EXPECT_EQ(result.joint_map.at("head_end"), "Neck_end");  // its End Site
  EXPECT_EQ(result.joint_map.at("left_hand_end"), "LeftHand_end");
  EXPECT_TRUE(result.unmapped.empty());
}

// A recording whose first frame stands somewhere else (a reference pose) is pointed out.
TEST(BvhRetarget, PelvisJumpBetweenFramesIsReported) {
  testing::TempDir dir;
  std::vector<std::string> frames = TestFrames();
  frames[1] = Frame({300, 0, 0}, {});  // 3 m (in centimetres) in 0.02 s
  std::ofstream(dir / "m.bvh") << SyntheticBvh(frames);
  const BvhRetargetResult result = RetargetBvhFile(dir / "m.bvh", StudioLikeSkeleton());
  ASSERT_FALSE(result.warnings.empty());
  EXPECT_NE(result.warnings.back().find("between frames 0 and 1"), std::string::npos) << result.warnings.back();
}

// A performer whose elbow bends about an axis tilted 35 degrees about the upper arm from the one
// the rest poses align with the target's hinge (the BVH's arm twisted at rest against the
// target's): the arm is turned about its bones so that the target's elbow bends about its hinge
// (the body's left-right axis made perpendicular to the upper arm), while every bone still points
// where the BVH's does. Without the turn the elbow bends 35 degrees off the hinge.
TEST(BvhRetarget, ElbowBendsAboutTheTargetsHinge) {
  constexpr double kTiltRad = 35.0 * M_PI / 180.0;
  // The BVH's left arm lies along +x, its front is +z: flexion turns about -y, tilted about x.
  const Vector3d axis = Eigen::AngleAxisd(kTiltRad, Vector3d::UnitX()) * Vector3d(0, -1, 0);
  std::vector<std::string> frames;
  for (int f = 0; f < 16; ++f) {
    const double bend = (30.0 + 6.0 * f) * M_PI / 180.0;
    const Vector3d zyx = Eigen::AngleAxisd(bend, axis).toRotationMatrix().eulerAngles(2, 1, 0) * 180.0 / M_PI;
    const Vector3d shoulder_zyx(-10.0 - 2.0 * f, 5.0, 0.0);  // the upper arm swings down and forwards
    frames.push_back(Frame({0, 0, 0}, {{kLArm, shoulder_zyx}, {kLForeArm, zyx}}));
  }
  testing::TempDir dir;
  std::ofstream(dir / "m.bvh") << SyntheticBvh(frames);
  const BvhMotion motion = ReadBvh(dir / "m.bvh");
  const Skeleton target = StudioLikeSkeleton();
  const std::vector<Vector3d> rest = target.RestPositions();
  const int shoulder = target.IndexOf("left_shoulder"), elbow = target.IndexOf("left_elbow");
  const Vector3d upper = (rest[elbow] - rest[shoulder]).normalized();
  const Vector3d lateral = rest[target.IndexOf("left_hip")] - rest[target.IndexOf("right_hip")];
  const Vector3d hinge = (lateral - lateral.dot(upper) * upper).normalized();
  // The largest angle between the target's elbow axis and its hinge over the bent frames.
  auto worst_off_hinge = [&](const BvhRetargetResult& result) {
    double worst = 0.0;
    for (const Pose& pose : result.poses) {
      const Eigen::AngleAxisd bend(pose.local_rotations[elbow]);
      EXPECT_GT(bend.angle(), 25.0 * M_PI / 180.0);
      worst = std::max(worst, std::acos(std::min(1.0, std::abs(bend.axis().dot(hinge)))));
    }
    return worst * 180.0 / M_PI;
  };
  BvhRetargetOptions keep;
  keep.min_hinge_turn_rad = std::numeric_limits<double>::infinity();
  const BvhRetargetResult kept = RetargetBvh(motion, target, keep, dir / "m.bvh");
  EXPECT_GT(worst_off_hinge(kept), 25.0);
  EXPECT_TRUE(kept.elbow_turns_deg.empty());

  const BvhRetargetResult result = RetargetBvh(motion, target, {}, dir / "m.bvh");
  EXPECT_LT(worst_off_hinge(result), 3.0);
  ASSERT_EQ(result.elbow_turns_deg.count("left"), 1u);
  EXPECT_NEAR(std::abs(result.elbow_turns_deg.at("left")), 35.0, 5.0);
  EXPECT_EQ(result.elbow_turns_deg.count("right"), 0u);  // a straight arm is left as it was
  ExpectBonesPointAsInTheBvh(motion, target, result, 1e-9);
}

TEST(BvhRetarget, RealCmuFile) {
  const std::string path = testing::SharedDataPath("bvh/cmu_131_01.bvh");
  if (path.empty()) GTEST_SKIP() << "shared data bvh/cmu_131_01.bvh not available";
  const Skeleton target = StudioLikeSkeleton();
  const BvhRetargetResult result = RetargetBvhFile(path, target);
  EXPECT_EQ(result.up_axis, 'y');
  EXPECT_EQ(result.unit, "cmu");
  EXPECT_EQ(result.joint_map.at("left_shoulder"), "LeftShoulder");
  EXPECT_EQ(result.joint_map.at("left_hip"), "LeftHip");
  EXPECT_EQ(result.joint_map.at("left_wrist"), "LeftWrist");
  EXPECT_EQ(result.joint_map.at("spine"), "Chest");
  EXPECT_EQ(result.joint_map.at("chest"), "Chest2");
  ASSERT_EQ(result.poses.size(), 994u);
  // The retargeted body keeps the BVH's vertical layout: head above pelvis and pelvis above
  // ankles, relative to their rest distances, as in the BVH (proportions differ).
  const BvhMotion motion = ReadBvh(path);
  const int hips = motion.skeleton.IndexOf("Hips"), head = motion.skeleton.IndexOf("Head");
  const int ankle = motion.skeleton.IndexOf("LeftAnkle");
  const int t_head = target.IndexOf("head"), t_ankle = target.IndexOf("left_ankle");
  const auto target_rest = target.RestPositions();
  const auto bvh_rest = motion.skeleton.RestPositions();
  double worst = 0.0;
  for (std::size_t f = 0; f < result.poses.size(); f += 10) {
    const auto p = JointPositions(target, result.poses[f]);
    const auto b = JointPositions(motion.skeleton, motion.frames[f]);
    auto up = [&](const Vector3d& v) { return (result.world_from_bvh * v).z(); };
    const double torso = (p[t_head] - p[0]).z() / (target_rest[t_head] - target_rest[0]).norm();
    const double bvh_torso = up(b[head] - b[hips]) / (bvh_rest[head] - bvh_rest[hips]).norm();
    const double leg = (p[0] - p[t_ankle]).z() / (target_rest[0] - target_rest[t_ankle]).norm();
    const double bvh_leg = up(b[hips] - b[ankle]) / (bvh_rest[hips] - bvh_rest[ankle]).norm();
    worst = std::max({worst, std::abs(torso - bvh_torso), std::abs(leg - bvh_leg)});
    EXPECT_NEAR(torso, bvh_torso, 0.08) << f;
    EXPECT_NEAR(leg, bvh_leg, 0.08) << f;
  }
  RecordProperty("worst_vertical_fraction_difference", std::to_string(worst));
}

}  // namespace
}  // namespace confluent
