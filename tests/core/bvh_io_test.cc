// BVH reading: channel orders, End Sites, forward kinematics, bad files, a real CMU file.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>

#include "core/bvh_io.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

// Root with 6 channels (Z Y X order), a child with X Z Y rotation order, and an End Site.
const char kBvh[] =
    "HIERARCHY\n"
    "ROOT Hips\n"
    "{\n"
    "  OFFSET 0 1 0\n"
    "  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n"
    "  JOINT Knee\n"
    "  {\n"
    "    OFFSET 0 -2 0\n"
    "    CHANNELS 3 Xrotation Zrotation Yrotation\n"
    "    End Site\n"
    "    {\n"
    "      OFFSET 0 0 3\n"
    "    }\n"
    "  }\n"
    "}\n"
    "MOTION\n"
    "Frames: 2\n"
    "Frame Time: 0.0333333\n"
    "0 0 0 0 0 0 0 0 0\n"
    "1 2 3 90 0 0 30 40 50\n";

Eigen::Matrix3d Rot(double deg, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(deg * M_PI / 180, axis).toRotationMatrix();
}

TEST(BvhIo, ParsesChannelOrdersEndSitesAndKinematics) {
  testing::TempDir dir;
  std::ofstream(dir / "a.bvh") << kBvh;
  BvhReadOptions options;
  options.scale = 0.5;
  const BvhMotion motion = ReadBvh(dir / "a.bvh", options);
  ASSERT_EQ(motion.skeleton.size(), 3);
  EXPECT_EQ(motion.skeleton.joints[2].name, "Knee_end");
  EXPECT_EQ(motion.skeleton.joints[2].parent, 1);
  EXPECT_EQ(motion.channels[1], (std::vector<std::string>{"Xrotation", "Zrotation", "Yrotation"}));
  EXPECT_TRUE(motion.channels[2].empty());
  EXPECT_NEAR(motion.frame_time_s, 0.0333333, 1e-12);
  ASSERT_EQ(motion.frames.size(), 2u);
  // Frame 1 by hand: root at offset + translation, rotations composed in channel order.
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  const Eigen::Matrix3d root = Rot(90, z) * Rot(0, y) * Rot(0, x);
  const Eigen::Matrix3d knee = Rot(30, x) * Rot(40, z) * Rot(50, y);
  const Eigen::Vector3d hips = 0.5 * Eigen::Vector3d(0, 1, 0) + 0.5 * Eigen::Vector3d(1, 2, 3);
  const Eigen::Vector3d knee_at = hips + root * (0.5 * Eigen::Vector3d(0, -2, 0));
  const Eigen::Vector3d end_at = knee_at + root * knee * (0.5 * Eigen::Vector3d(0, 0, 3));
  const auto positions = JointPositions(motion.skeleton, motion.frames[1]);
  EXPECT_LT((positions[0] - hips).norm(), 1e-9);
  EXPECT_LT((positions[1] - knee_at).norm(), 1e-9);
  EXPECT_LT((positions[2] - end_at).norm(), 1e-9);
  // Without End Sites, and converted to Z up: the rest knee is below the hips along -z.
  options.include_end_sites = false;
  options.y_up_to_z_up = true;
  const BvhMotion zup = ReadBvh(dir / "a.bvh", options);
  ASSERT_EQ(zup.skeleton.size(), 2);
  EXPECT_LT((zup.skeleton.joints[1].offset_in_parent - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
  const auto zup_positions = JointPositions(zup.skeleton, zup.frames[1]);
  Eigen::Matrix3d axes;
  axes << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  EXPECT_LT((zup_positions[1] - axes * knee_at).norm(), 1e-9);
}

// Bandai Namco's layout: a root that never moves above hips that carry the travel in their own
// translation channels (and every joint with 6 channels that repeat its offset).
TEST(BvhIo, MotionlessRootAboveTravellingHipsGivesWayToThem) {
  testing::TempDir dir;
  std::ofstream(dir / "static_root.bvh") << "HIERARCHY\nROOT joint_Root\n{\n  OFFSET 1 0 0\n"
                                            "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                                            "  JOINT Hips\n  {\n    OFFSET 0 90 0\n"
                                            "    CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                                            "    JOINT Spine\n    {\n      OFFSET 0 10 0\n"
                                            "      CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                                            "      End Site\n      {\n        OFFSET 0 5 0\n      }\n    }\n  }\n}\n"
                                            "MOTION\nFrames: 2\nFrame Time: 0.5\n"
                                            "0 0 0 0 0 90  10 90 0 0 0 0  0 10 0 0 0 0\n"
                                            "0 0 0 0 0 90  20 90 5 90 0 0  0 10 0 0 0 0\n";
  const BvhMotion motion = ReadBvh(dir / "static_root.bvh");
  EXPECT_TRUE(motion.warnings.empty()) << motion.warnings[0];
  ASSERT_EQ(motion.skeleton.size(), 3);  // Hips, Spine, Spine_end
  EXPECT_EQ(motion.skeleton.joints[0].name, "Hips");
  EXPECT_EQ(motion.skeleton.joints[0].parent, -1);
  EXPECT_EQ(motion.channels.size(), 3u);
  // The root: at (1, 0, 0), turned 90 degrees about y (x -> -z). The hips stand at the root plus
  // the turned channel translation, the spine 10 up from them, turned with the hips.
  const Eigen::Matrix3d root = Rot(90, Eigen::Vector3d::UnitY());
  const Eigen::Vector3d root_at(1, 0, 0);
  const Eigen::Vector3d hips[2] = {root_at + root * Eigen::Vector3d(10, 90, 0), root_at + root * Eigen::Vector3d(20, 90, 5)};
  const Eigen::Matrix3d hips_turn[2] = {root, root * Rot(90, Eigen::Vector3d::UnitZ())};
  for (int f = 0; f < 2; ++f) {
    const auto p = JointPositions(motion.skeleton, motion.frames[f]);
    EXPECT_LT((p[0] - hips[f]).norm(), 1e-9) << f;
    EXPECT_LT((p[1] - (hips[f] + hips_turn[f] * Eigen::Vector3d(0, 10, 0))).norm(), 1e-9) << f;
    EXPECT_LT((p[2] - (hips[f] + hips_turn[f] * Eigen::Vector3d(0, 15, 0))).norm(), 1e-9) << f;
  }
}

// A moving root keeps its place; the hips' translation channels cannot be kept and are named.
TEST(BvhIo, TranslationOfAJointBelowAMovingRootIsIgnoredWithAWarning) {
  testing::TempDir dir;
  std::ofstream(dir / "moving_root.bvh") << "HIERARCHY\nROOT joint_Root\n{\n  OFFSET 0 0 0\n"
                                            "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                                            "  JOINT Hips\n  {\n    OFFSET 0 90 0\n"
                                            "    CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                                            "    End Site\n    {\n      OFFSET 0 5 0\n    }\n  }\n}\n"
                                            "MOTION\nFrames: 2\nFrame Time: 0.5\n"
                                            "0 0 0 0 0 0  10 90 0 0 0 0\n"
                                            "1 0 0 0 0 0  20 90 5 0 0 0\n";
  const BvhMotion motion = ReadBvh(dir / "moving_root.bvh");
  EXPECT_EQ(motion.skeleton.joints[0].name, "joint_Root");
  ASSERT_EQ(motion.warnings.size(), 1u);
  EXPECT_NE(motion.warnings[0].find("Hips"), std::string::npos) << motion.warnings[0];
}

TEST(BvhIo, BadFilesNameFileAndLine) {
  testing::TempDir dir;
  auto expect_error = [&](const std::string& text, const std::string& needle) {
    std::ofstream(dir / "bad.bvh") << text;
    try {
      ReadBvh(dir / "bad.bvh");
      ADD_FAILURE() << "no error";
    } catch (const InputError& error) {
      const std::string what = error.what();
      EXPECT_NE(what.find(dir / "bad.bvh"), std::string::npos) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
    }
  };
  std::string text = kBvh;
  // Truncated inside the motion block and inside the hierarchy.
  expect_error(text.substr(0, text.size() - 20), "line 20: frame 1 has too few values");
  expect_error(text.substr(0, text.find("MOTION") - 10), "unexpected end of file");
  expect_error(std::string(kBvh).substr(0, text.rfind("1 2 3")), "ends after 1 of 2 frames");
  std::string unknown = kBvh;
  unknown.replace(unknown.find("Xrotation Zrotation"), 9, "Wrotation");
  expect_error(unknown, "line 9: unknown channel 'Wrotation'");
  std::string extra = kBvh;
  extra += "1 2 3 4 5 6 7 8 9\n";
  expect_error(extra, "after the last frame");
  expect_error("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 zero 0\n", "line 4: expected a number");
  EXPECT_THROW(ReadBvh(dir / "missing.bvh"), InputError);
}

TEST(BvhIo, WrittenMotionReadsBackWithTheSameJointPositions) {
  // A branching chain (a root with two children, one of them with a child of its own), Z-up,
  // metres, with arbitrary rotations: written as Y-up centimetres, read back with the inverse.
  Skeleton skeleton;
  skeleton.joints = {{"hips", -1, {0.1, -0.2, 0.9}},
                     {"spine", 0, {0.0, 0.0, 0.25}},
                     {"neck", 1, {0.02, 0.0, 0.3}},
                     {"leg", 0, {0.1, 0.0, -0.1}}};
  std::vector<Pose> poses;
  for (int f = 0; f < 3; ++f) {
    Pose pose = Pose::Rest(skeleton.size());
    pose.root_translation = Eigen::Vector3d(0.05 * f, -0.1, 0.02 * f);
    for (int j = 0; j < skeleton.size(); ++j)
      pose.local_rotations[j] = Eigen::AngleAxisd(0.3 + 0.4 * f + 0.2 * j, Eigen::Vector3d(1, 2 - j, 0.5 * f).normalized());
    poses.push_back(pose);
  }
  const testing::TempDir dir;
  WriteBvh(dir / "motion.bvh", skeleton, poses, 1.0 / 30);
  BvhReadOptions options;
  options.scale = 0.01;
  options.y_up_to_z_up = true;
  const BvhMotion motion = ReadBvh(dir / "motion.bvh", options);
  EXPECT_NEAR(motion.frame_time_s, 1.0 / 30, 1e-6);
  ASSERT_EQ(motion.frames.size(), poses.size());
  // The childless "neck" and "leg" become End Sites named after their parents.
  EXPECT_GE(motion.skeleton.IndexOf("spine_end"), 0);
  EXPECT_GE(motion.skeleton.IndexOf("hips_end"), 0);
  for (std::size_t f = 0; f < poses.size(); ++f) {
    const auto expected = JointPositions(skeleton, poses[f]);
    const auto actual = JointPositions(motion.skeleton, motion.frames[f]);
    ASSERT_EQ(actual.size(), expected.size());
    for (int j = 0; j < skeleton.size(); ++j) EXPECT_LT((expected[j] - actual[j]).norm(), 1e-5) << "frame " << f << " joint " << j;
  }
}

TEST(BvhIo, WritingBelowARegularFileIsOutputError) {
  const testing::TempDir dir;
  std::ofstream(dir / "not_a_folder") << "x";
  Skeleton skeleton;
  skeleton.joints = {{"root", -1, {0, 0, 1}}, {"tip", 0, {0, 0, 0.5}}};
  EXPECT_THROW(WriteBvh(dir / "not_a_folder/motion.bvh", skeleton, {Pose::Rest(2)}, 0.04), OutputError);
}

TEST(BvhIo, ReadsRealCmuFile) {
  const std::string path = testing::SharedDataPath("bvh/cmu_131_01.bvh");
  if (path.empty()) GTEST_SKIP() << "shared data bvh/cmu_131_01.bvh not available";
  const BvhMotion motion = ReadBvh(path);
  std::ifstream file(path);
  std::string line;
  int frames = -1;
  while (std::getline(file, line))
    if (line.rfind("Frames:", 0) == 0) frames = std::stoi(line.substr(7));
  EXPECT_EQ(static_cast<int>(motion.frames.size()), frames);
  EXPECT_GE(motion.skeleton.size(), 25);
  EXPECT_TRUE(motion.skeleton.IsTopologicallyOrdered());
  for (const Pose& pose : motion.frames)
    for (const auto& position : JointPositions(motion.skeleton, pose)) ASSERT_TRUE(position.allFinite());
}

}  // namespace
}  // namespace confluent
