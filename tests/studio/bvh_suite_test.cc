// The motion suite's BVH clips (../shared/data/bvh/suite/, skipped when absent), performed by the
// studio actor as `synth --bvh` performs them: each source skeleton (CMU, SFU, Bandai Namco,
// Perfume, three.js, a Z-up file without a head joint) gives an actor of the right height,
// upright at the first frame with the shoulders square to the hips, whose every segment moves,
// whose trunk and neck never twist half round about their bones, whose hands bend at the wrists
// as the BVH's do, and whose pelvis stays in the capture volume.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "core/body_model.h"
#include "core/body_segments.h"
#include "studio/actor.h"
#include "studio/motion.h"
#include "studio/rig.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using Eigen::Vector3d;

struct SuiteClip {
  const char* file;
  double start_s;  // where the suite's excerpt starts
  bool in_place;   // performed on the spot (the clip travels further than the cameras see)
};

class BvhSuiteClip : public ::testing::TestWithParam<SuiteClip> {};

TEST_P(BvhSuiteClip, ActorIsUprightOfItsHeightMovesEverySegmentAndStaysInView) {
  const std::string path = testing::SharedDataPath(std::string("bvh/suite/") + GetParam().file);
  if (path.empty()) GTEST_SKIP() << "shared data bvh/suite/" << GetParam().file << " not available";
  const StudioActorOptions actor_options;
  const Skeleton skeleton = MakeStudioSkeleton(actor_options);
  StudioMotionOptions options;
  options.bvh_path = path;
  options.fps = 25.0;
  options.num_frames = 125;  // 5 s
  options.bvh_start_s = GetParam().start_s;
  BvhRetargetResult retarget;
  std::vector<Pose> poses = BvhPerformance(skeleton, options, &retarget);
  ASSERT_GE(poses.size(), 60u);
  // Placed in the default studio as `synth` places it.
  const StudioRigOptions rig_options;
  const double volume = CaptureVolumeRadius(MakeStudioRig(rig_options), rig_options.num_ring_cameras,
                                            rig_options.target_in_world, actor_options.height_m);
  const PerformancePlacement placement = KeepPerformanceInVolume(
      &poses, skeleton, rig_options.target_in_world.head<2>(), volume, options.fps, GetParam().in_place, path);

  // Height and uprightness at the first frame.
  const std::vector<Vector3d> first = JointPositions(skeleton, poses[0]);
  double lowest = 1e9;
  for (int j : {kJointLeftAnkle, kJointRightAnkle, kJointLeftToe, kJointRightToe}) lowest = std::min(lowest, first[j].z());
  const double height = first[kJointHeadEnd].z() - lowest;
  const Vector3d trunk = (first[kJointNeck] - first[kJointPelvis]).normalized();
  const double lean_deg = std::acos(std::clamp(trunk.z(), -1.0, 1.0)) * 180.0 / M_PI;
  // The shoulders' left-right axis against the hips' (a torso turned round on its pelvis).
  const Vector3d shoulders = first[kJointLeftShoulder] - first[kJointRightShoulder];
  const Vector3d hips = first[kJointLeftHip] - first[kJointRightHip];
  const double twist_deg =
      std::acos(std::clamp(shoulders.head<2>().normalized().dot(hips.head<2>().normalized()), -1.0, 1.0)) * 180.0 / M_PI;

  // How far each segment turns over the clip (largest angle from its first-frame orientation).
  const std::array<int, kNumBodySegments> segment_joint = StudioSegmentJoints();
  std::array<double, kNumBodySegments> turned{};
  const auto first_world = WorldFromJoint(skeleton, poses[0]);
  double farthest = 0.0, largest_bone_twist = 0.0;
  for (const Pose& pose : poses) {
    const auto world = WorldFromJoint(skeleton, pose);
    for (int s = 0; s < kNumBodySegments; ++s) {
      const Eigen::Matrix3d delta = world[segment_joint[s]].linear() * first_world[segment_joint[s]].linear().transpose();
      turned[s] = std::max(turned[s], Eigen::AngleAxisd(delta).angle() * 180.0 / M_PI);
    }
    farthest = std::max(farthest, world[kJointPelvis].translation().head<2>().norm());
    // Twist of each trunk and neck joint about its own bone against its parent (a spine turned
    // half round on the pelvis, a head facing backwards: joint positions cannot show it).
    for (int j : {kJointSpine, kJointChest, kJointNeck, kJointHead}) {
      const Vector3d axis = skeleton.joints[j + 1].offset_in_parent.normalized();  // spine->chest ... head->head_end
      const Eigen::Quaterniond& q = pose.local_rotations[j];
      double angle = 2.0 * std::atan2(q.vec().dot(axis), q.w()) * 180.0 / M_PI;
      angle = std::abs(std::remainder(angle, 360.0));
      largest_bone_twist = std::max(largest_bone_twist, angle);
    }
  }
  double least_turn = 1e9;
  for (double t : turned) least_turn = std::min(least_turn, t);
  std::printf("%-34s unit %-4s up %c height %.3f lean %.1f deg twist %.1f deg least segment turn %.1f deg travel "
              "%.2f m, placed within %.2f of %.2f m, trunk/neck bone twist up to %.0f deg\n", GetParam().file,
              retarget.unit.c_str(), retarget.up_axis, height, lean_deg, twist_deg, least_turn, placement.travel_m, farthest,
              volume, largest_bone_twist);
  for (const auto& w : retarget.warnings) std::printf("  warning: %s\n", w.c_str());
  for (const auto& u : retarget.unmapped) std::printf("  unmapped: %s\n", u.c_str());

  EXPECT_NEAR(height, actor_options.height_m, 0.15 * actor_options.height_m);
  EXPECT_LT(lean_deg, 30.0);
  EXPECT_LT(twist_deg, 60.0);
  EXPECT_GT(least_turn, 3.0);
  EXPECT_LE(farthest, volume + 1e-9);
  EXPECT_LT(largest_bone_twist, 90.0);  // a neck turns about 80 degrees at most
}

// The bend at b of the chain a -> b -> c.
double BendDeg(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  return std::acos(std::clamp((b - a).normalized().dot((c - b).normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

// The hands bend at the wrists as the BVH's hands do: the angle between forearm and hand, frame by
// frame, against the BVH's own (its mapped elbow, wrist and the first joint past the wrist that
// does not lie on it: CMU's finger base has an offset of zero). A BVH whose hand ends where it
// starts (Bandai Namco's End Sites) says nothing of the hand's direction: the hand then continues
// the forearm, turned only by the BVH's wrist rotation (its bend at most that rotation's angle).
// Before, such hands (and CMU's) kept the pelvis's orientation at the reference pose: bent by 50
// degrees in every frame, or folded back onto the forearm (Bandai Namco's, 154 to 180 degrees).
TEST_P(BvhSuiteClip, HandsBendAsTheBvhHandsBend) {
  const std::string path = testing::SharedDataPath(std::string("bvh/suite/") + GetParam().file);
  if (path.empty()) GTEST_SKIP() << "shared data bvh/suite/" << GetParam().file << " not available";
  const Skeleton skeleton = MakeStudioSkeleton(StudioActorOptions());
  const BvhMotion motion = ReadBvh(path);
  const BvhRetargetResult result = RetargetBvh(motion, skeleton, {}, path);
  const Skeleton& bvh = motion.skeleton;
  std::vector<int> first_child(bvh.size(), -1);
  for (int j = bvh.size() - 1; j > 0; --j) first_child[bvh.joints[j].parent] = j;
  const std::vector<Vector3d> bvh_rest = bvh.RestPositions();
  const Pose reference = result.reference_frame >= 0 ? motion.frames[result.reference_frame] : Pose::Rest(bvh.size());
  for (const char* side : {"left", "right"}) {
    const std::string s(side);
    const int wrist = skeleton.IndexOf(s + "_wrist"), elbow = skeleton.IndexOf(s + "_elbow");
    const int hand_end = skeleton.IndexOf(s + "_hand_end");
    const int b_wrist = bvh.IndexOf(result.joint_map.at(s + "_wrist")), b_elbow = bvh.IndexOf(result.joint_map.at(s + "_elbow"));
    int b_hand = result.joint_map.count(s + "_hand_end") ? bvh.IndexOf(result.joint_map.at(s + "_hand_end")) : first_child[b_wrist];
    while (b_hand >= 0 && (bvh_rest[b_hand] - bvh_rest[b_wrist]).norm() < 1e-6) b_hand = first_child[b_hand];
    // Without a direction: the wrist's rotation against the elbow's, relative to the reference
    // pose's, bounds the bend (a hand in line with the forearm there).
    auto wrist_in_elbow = [&](const Pose& pose) {
      const auto world = WorldFromJoint(bvh, pose);
      return Eigen::Matrix3d(world[b_elbow].linear().transpose() * world[b_wrist].linear());
    };
    const Eigen::Matrix3d reference_wrist = wrist_in_elbow(reference);
    double worst_difference = 0.0, largest = 0.0;
    for (std::size_t f = 0; f < motion.frames.size(); f += 5) {
      const std::vector<Vector3d> p = JointPositions(skeleton, result.poses[f]);
      const double bend = BendDeg(p[elbow], p[wrist], p[hand_end]);
      largest = std::max(largest, bend);
      double difference = 0.0;
      if (b_hand >= 0) {
        const std::vector<Vector3d> q = JointPositions(bvh, motion.frames[f]);
        difference = std::abs(bend - BendDeg(q[b_elbow], q[b_wrist], q[b_hand]));
      } else {
        const double turn = Eigen::AngleAxisd(reference_wrist.transpose() * wrist_in_elbow(motion.frames[f])).angle();
        difference = std::max(0.0, bend - turn * 180.0 / M_PI);
      }
      worst_difference = std::max(worst_difference, difference);
    }
    std::printf("%-34s %-5s hand %s: wrist bend up to %.0f deg, %.1f deg past the BVH's at worst\n", GetParam().file,
                side, b_hand < 0 ? "without a direction in the BVH" : bvh.joints[b_hand].name.c_str(), largest,
                worst_difference);
    EXPECT_LT(worst_difference, 3.0) << side;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Suite, BvhSuiteClip,
    ::testing::Values(SuiteClip{"threejs_pirouette.bvh", 0, true}, SuiteClip{"cmu_05_20_modern_dance.bvh", 0, false},
                      SuiteClip{"cmu_94_01_indian_dance.bvh", 0, true}, SuiteClip{"cmu_01_01_forward_jumps_turn.bvh", 0, true},
                      SuiteClip{"perfume_B_dance.bvh", 1.0, true}, SuiteClip{"bvhviewer_jump_from_stand.bvh", 0, false},
                      SuiteClip{"sfu_0007_Cartwheel001.bvh", 0, true}, SuiteClip{"sfu_0005_Jogging001.bvh", 0, true},
                      SuiteClip{"sfu_0005_JumpRope001.bvh", 0, false}, SuiteClip{"sfu_0005_SideSkip001.bvh", 0, true},
                      SuiteClip{"bandai_kick_normal_001.bvh", 0, false}, SuiteClip{"bandai_punch_normal_002.bvh", 0, false}),
    [](const ::testing::TestParamInfo<SuiteClip>& info) {
      std::string name = info.param.file;
      name = name.substr(0, name.find('.'));
      for (char& c : name) if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      return name;
    });

}  // namespace
}  // namespace confluent
