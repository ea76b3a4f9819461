// Joints triangulated from 2D landmarks (tracking/landmark_joints.h). Ground truth: the
// template's joints in a known pose, projected into a ring of cameras, with the faults a
// detector makes (a camera that misplaces a wrist, cameras that swap left and right).

#include <gtest/gtest.h>

#include <random>

#include "tests/support/camera_ring.h"
#include "tests/support/template_masks.h"
#include "tracking/body_template.h"
#include "tracking/landmark_joints.h"

namespace confluent {
namespace {

// The BlazePose landmark of each template joint that the triangulation places.
constexpr std::pair<int, int> kLandmarkOf[] = {
    {kJointLeftShoulder, 11}, {kJointRightShoulder, 12}, {kJointLeftElbow, 13}, {kJointRightElbow, 14},
    {kJointLeftWrist, 15},    {kJointRightWrist, 16},    {kJointLeftHip, 23},   {kJointRightHip, 24},
    {kJointLeftKnee, 25},     {kJointRightKnee, 26},     {kJointLeftAnkle, 27}, {kJointRightAnkle, 28},
    {kJointLeftToe, 31},      {kJointRightToe, 32},
};

TemplatePose Reaching() {
  TemplatePose pose;
  pose.root_translation = Eigen::Vector3d(0.2, -0.1, 0.0);
  pose.root_rotation = Eigen::Vector3d(0, 0, 0.7);
  pose.dofs[kJointLeftShoulder] = {0.0, 0.9, 0.3};
  pose.dofs[kJointLeftElbow] = {1.3, 0, 0};
  pose.dofs[kJointRightShoulder] = {-1.0, -0.2, 0.0};
  pose.dofs[kJointRightKnee] = {1.0, 0, 0};
  return pose;
}

// The direction the body of Reaching() faces (the template faces +y at rest).
Eigen::Vector3d Forward() { return Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d::UnitY(); }

// Each camera's landmarks of `joints` (and the hands' knuckles, a nose ahead of the head, heels
// behind the ankles), with `noise_px` of Gaussian noise, all visible.
std::vector<BodyLandmarks> Project(const Rig& rig, const std::vector<Eigen::Vector3d>& joints, double noise_px) {
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, noise_px);
  std::vector<BodyLandmarks> views(rig.size());
  for (int c = 0; c < rig.size(); ++c) {
    for (Eigen::Vector3f& landmark : views[c]) landmark = Eigen::Vector3f(0, 0, 0);  // unseen
    auto add = [&](int landmark, const Eigen::Vector3d& point) {
      const Eigen::Vector2d px = rig.cameras[c].Project(point);
      views[c][landmark] = Eigen::Vector3f(px.x() + noise(random), px.y() + noise(random), 0.95f);
    };
    for (const auto& [joint, landmark] : kLandmarkOf) add(landmark, joints[joint]);
    for (int side = 0; side < 2; ++side) {  // the index and pinky knuckles, 2 cm either side of the hand's axis
      const int wrist = side ? kJointRightWrist : kJointLeftWrist;
      const Eigen::Vector3d across = (joints[wrist + 1] - joints[wrist]).cross(Eigen::Vector3d::UnitZ()).normalized();
      add(19 + side, testing::KnucklesOf(joints, wrist) + 0.02 * across);
      add(17 + side, testing::KnucklesOf(joints, wrist) - 0.02 * across);
    }
    add(0, joints[kJointHead] + 0.1 * Forward());
    add(29, joints[kJointLeftAnkle] - 0.06 * Forward() - Eigen::Vector3d(0, 0, 0.05));
    add(30, joints[kJointRightAnkle] - 0.06 * Forward() - Eigen::Vector3d(0, 0, 0.05));
  }
  return views;
}

std::vector<const BodyLandmarks*> Pointers(const std::vector<BodyLandmarks>& views) {
  std::vector<const BodyLandmarks*> out;
  for (const BodyLandmarks& v : views) out.push_back(&v);
  return out;
}

void SwapLeftRight(BodyLandmarks* view) {
  for (int k = 1; k + 1 < kBodyLandmarks; k += 2) std::swap((*view)[k], (*view)[k + 1]);
}

double WorstError(const LandmarkJoints& found, const std::vector<Eigen::Vector3d>& truth) {
  double worst = 0;
  for (const auto& [joint, landmark] : kLandmarkOf) {
    if (!found.known(joint)) return 1e9;
    worst = std::max(worst, (found.position[joint] - truth[joint]).norm());
  }
  return worst;
}

// A body reaching out, turned 40 degrees, in a ring of 8 cameras at 512x384.
class Triangulation : public ::testing::Test {
 protected:
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.75);
  const Rig rig = testing::CameraRing(8, 512, 384);
  const std::vector<Eigen::Vector3d> truth = body.JointPositions(shape, Reaching());
};

TEST_F(Triangulation, EveryLimbJointIsPlacedFromNoisyLandmarks) {
  const LandmarkJoints found = TriangulateLandmarkJoints(rig, Pointers(Project(rig, truth, 1.0)));
  EXPECT_EQ(found.num_known(), 14);
  EXPECT_LT(WorstError(found, truth), 0.02);  // 1 px of noise at 3.6 m: about 6 mm per camera
  for (const auto& [joint, landmark] : kLandmarkOf) {
    EXPECT_EQ(found.cameras[joint], 8) << BodyJointNames()[joint];
    EXPECT_LT(found.rms_px[joint], 3.0);
  }
  EXPECT_FALSE(found.known(kJointHead));
  EXPECT_FALSE(found.known(kJointPelvis));
  for (int side = 0; side < 2; ++side) {
    const int wrist = side ? kJointRightWrist : kJointLeftWrist;
    EXPECT_EQ(found.knuckle_cameras[side], 8);
    EXPECT_LT((found.knuckles[side] - testing::KnucklesOf(truth, wrist)).norm(), 0.02) << side;
  }
}

TEST_F(Triangulation, CamerasThatSwapLeftAndRightOrMisplaceAWristAreOutvoted) {
  std::vector<BodyLandmarks> views = Project(rig, truth, 1.0);
  SwapLeftRight(&views[2]);  // a detector seeing the back calls the left side right
  SwapLeftRight(&views[5]);
  views[0][15] += Eigen::Vector3f(60, -40, 0);  // camera 0 misplaces the left wrist
  const LandmarkJoints found = TriangulateLandmarkJoints(rig, Pointers(views));
  EXPECT_LT(WorstError(found, truth), 0.02);
  EXPECT_EQ(found.cameras[kJointLeftWrist], 7);  // camera 0 disagrees
  EXPECT_EQ(found.cameras[kJointRightElbow], 8);  // the swapped cameras agree once swapped back
  EXPECT_EQ(found.cameras[kJointLeftShoulder], 8);
  // The sides settled as the joints':
  EXPECT_LT((found.knuckles[0] - testing::KnucklesOf(truth, kJointLeftWrist)).norm(), 0.02);
  EXPECT_LT((found.knuckles[1] - testing::KnucklesOf(truth, kJointRightWrist)).norm(), 0.02);
}

// A detector that sees the back takes it for the front: five cameras of eight swap the sides.
// Where the nose and the toes point says which side is left; without them, most cameras do.
TEST_F(Triangulation, TheFrontThatTheNoseAndToesShowDecidesWhichSideIsLeft) {
  std::vector<BodyLandmarks> views = Project(rig, truth, 1.0);
  for (int c : {0, 1, 3, 4, 6}) SwapLeftRight(&views[c]);
  const LandmarkJoints found = TriangulateLandmarkJoints(rig, Pointers(views));
  EXPECT_LT(WorstError(found, truth), 0.02);
  // The heels hidden: the nose.
  for (BodyLandmarks& view : views)
    for (int landmark : {29, 30}) view[landmark].z() = 0.1f;
  EXPECT_LT(WorstError(TriangulateLandmarkJoints(rig, Pointers(views)), truth), 0.02);
  // The nose hidden too: the majority's labelling, swapped.
  for (BodyLandmarks& view : views) view[0].z() = 0.1f;
  const LandmarkJoints majority = TriangulateLandmarkJoints(rig, Pointers(views));
  ASSERT_TRUE(majority.known(kJointLeftWrist));
  EXPECT_LT((majority.position[kJointLeftWrist] - truth[kJointRightWrist]).norm(), 0.02);
  EXPECT_LT((majority.position[kJointRightWrist] - truth[kJointLeftWrist]).norm(), 0.02);
}

TEST_F(Triangulation, AJointFewCamerasSeeOrAgreeOnStaysUnknown) {
  std::vector<BodyLandmarks> views = Project(rig, truth, 1.0);
  // The left knee: visible in three cameras only, two of which misplace it, each its own way.
  for (int c = 0; c < 8; ++c) views[c][25].z() = c < 3 ? 0.9f : 0.1f;
  views[1][25] += Eigen::Vector3f(80, 0, 0);
  views[2][25] += Eigen::Vector3f(0, 80, 0);
  // The right ankle: hidden everywhere but one camera (and that camera has no landmarks).
  for (int c = 1; c < 8; ++c) views[c][28].z() = 0.2f;
  std::vector<const BodyLandmarks*> pointers = Pointers(views);
  pointers[7] = nullptr;  // a camera without landmarks
  const LandmarkJoints found = TriangulateLandmarkJoints(rig, pointers);
  EXPECT_FALSE(found.known(kJointLeftKnee));
  EXPECT_TRUE(found.known(kJointRightKnee));  // each joint on its own
  EXPECT_FALSE(found.known(kJointRightAnkle));
  EXPECT_TRUE(found.known(kJointLeftAnkle));
  EXPECT_TRUE(found.known(kJointLeftWrist));
  EXPECT_EQ(found.cameras[kJointLeftWrist], 7);
  // The left hand's pinky hidden from all but two cameras: its knuckles stay unknown.
  for (int c = 2; c < 8; ++c) views[c][17].z() = 0.1f;
  const LandmarkJoints without_pinky = TriangulateLandmarkJoints(rig, Pointers(views));
  EXPECT_EQ(without_pinky.knuckle_cameras[0], 0);
  EXPECT_GT(without_pinky.knuckle_cameras[1], 0);
}

}  // namespace
}  // namespace confluent
