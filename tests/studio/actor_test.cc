// The studio actor: watertight body mesh, segments, skinning and the default performance.

#include <gtest/gtest.h>

#include <set>

#include "core/error.h"
#include "core/mesh_validation.h"
#include "core/skinning.h"
#include "studio/actor.h"
#include "studio/motion.h"

namespace confluent {
namespace {

const StudioActor& TinyActor() {
  static const StudioActor actor = [] {
    StudioActorOptions options;
    options.target_triangles = 12000;
    return BuildStudioActor(options);
  }();
  return actor;
}

TEST(StudioActor, TinyMeshIsWatertightSingleComponentWithAllSegments) {
  const StudioActor& actor = TinyActor();
  const MeshReport report = ValidateMesh(actor.mesh);
  EXPECT_TRUE(report.is_watertight()) << report.ToString();
  EXPECT_TRUE(report.is_clean()) << report.ToString();
  EXPECT_EQ(report.num_components, 1);
  EXPECT_GT(actor.mesh.num_faces(), 9000);
  EXPECT_LT(actor.mesh.num_faces(), 16000);
  ASSERT_TRUE(actor.mesh.has_colors());
  ASSERT_TRUE(actor.mesh.has_face_labels());
  std::set<int> labels(actor.mesh.face_labels.begin(), actor.mesh.face_labels.end());
  EXPECT_EQ(static_cast<int>(labels.size()), kNumBodySegments);
  EXPECT_GE(actor.mesh.colors.minCoeff(), 0.0f);
  EXPECT_LE(actor.mesh.colors.maxCoeff(), 1.0f);
  // Standing on the floor, about 1.75 m tall, facing +y (the nose is the front-most head point).
  EXPECT_NEAR(actor.mesh.vertices.col(2).minCoeff(), 0.0, 0.02);
  EXPECT_NEAR(actor.mesh.vertices.col(2).maxCoeff(), 1.75, 0.03);
}

TEST(StudioActor, DefaultDetailHasMoreThan100KTriangles) {
  const StudioActor actor = BuildStudioActor();
  EXPECT_GE(actor.mesh.num_faces(), 100000);
  const MeshReport report = ValidateMesh(actor.mesh);
  EXPECT_TRUE(report.is_watertight()) << report.ToString();
  EXPECT_EQ(report.num_components, 1);
}

TEST(StudioActor, SkeletonHasTemplateJointsAndHeight) {
  StudioActorOptions options;
  options.height_m = 1.5;
  const Skeleton skeleton = MakeStudioSkeleton(options);
  ASSERT_TRUE(skeleton.IsTopologicallyOrdered());
  for (const char* name : {"pelvis", "spine", "chest", "neck", "head", "left_shoulder", "right_elbow", "left_wrist",
                           "right_hip", "left_knee", "right_ankle", "left_toe"})
    EXPECT_GE(skeleton.IndexOf(name), 0) << name;
  const auto rest = skeleton.RestPositions();
  EXPECT_NEAR(rest[skeleton.IndexOf("head_end")].z(), 1.5, 1e-9);
  // The actor's left is -x.
  EXPECT_LT(rest[skeleton.IndexOf("left_shoulder")].x(), 0.0);
}

TEST(StudioActor, WeightsAreValid) {
  const StudioActor& actor = TinyActor();
  EXPECT_NO_THROW(actor.weights.Check(actor.skeleton.size(), "actor"));
  EXPECT_EQ(actor.weights.num_vertices(), actor.mesh.num_vertices());
}

TEST(StudioActor, SkinningReproducesRestPose) {
  const StudioActor& actor = TinyActor();
  const Pose rest = Pose::Rest(actor.skeleton.size());
  for (SkinningMethod method : {SkinningMethod::kLinear, SkinningMethod::kDualQuaternion}) {
    const RowMatrixX3d posed = SkinVertices(actor.mesh.vertices, actor.weights, actor.skeleton, rest, method);
    EXPECT_LT((posed - actor.mesh.vertices).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(StudioActor, SingleBoneRotationMovesItsSubtreeRigidly) {
  const StudioActor& actor = TinyActor();
  const Skeleton& skeleton = actor.skeleton;
  const int elbow = skeleton.IndexOf("left_elbow");
  std::vector<bool> in_subtree(skeleton.size(), false);
  for (int j = 0; j < skeleton.size(); ++j)
    in_subtree[j] = j == elbow || (skeleton.joints[j].parent >= 0 && in_subtree[skeleton.joints[j].parent]);
  Pose pose = Pose::Rest(skeleton.size());
  pose.local_rotations[elbow] = Eigen::Quaterniond(Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.3, 0.8, 0.2).normalized()));
  const Eigen::Isometry3d expected = SkinningTransforms(skeleton, pose)[elbow];
  for (SkinningMethod method : {SkinningMethod::kLinear, SkinningMethod::kDualQuaternion}) {
    const RowMatrixX3d posed = SkinVertices(actor.mesh.vertices, actor.weights, skeleton, pose, method);
    int rigid = 0, fixed = 0;
    for (int v = 0; v < actor.mesh.num_vertices(); ++v) {
      double inside = 0.0;
      for (int k = 0; k < 4; ++k)
        if (actor.weights.joints(v, k) >= 0 && in_subtree[actor.weights.joints(v, k)]) inside += actor.weights.weights(v, k);
      const Eigen::Vector3d p = actor.mesh.vertices.row(v).transpose();
      const Eigen::Vector3d q = posed.row(v).transpose();
      if (inside > 1.0 - 1e-12) {
        EXPECT_LT((q - expected * p).norm(), 1e-9) << "vertex " << v;
        ++rigid;
      } else if (inside < 1e-12) {
        EXPECT_LT((q - p).norm(), 1e-12) << "vertex " << v;
        ++fixed;
      }
    }
    EXPECT_GT(rigid, 100);   // the forearm and hand
    EXPECT_GT(fixed, 5000);  // everything else
  }
}

TEST(StudioMotion, DefaultPerformanceHasLargeVariedMotionAndFeetOnTheFloor) {
  const StudioActor& actor = TinyActor();
  const Skeleton& skeleton = actor.skeleton;
  const std::vector<Pose> poses = DefaultPerformance(skeleton);
  ASSERT_EQ(poses.size(), 100u);
  EXPECT_GE(DefaultPerformanceDuration(), 4.0);
  const int head = skeleton.IndexOf("head_end"), lw = skeleton.IndexOf("left_wrist"), rw = skeleton.IndexOf("right_wrist");
  const int pelvis = 0, rtoe = skeleton.IndexOf("right_toe");
  bool arms_up = false, kick = false, crouch = false, turned_back = false;
  for (std::size_t f = 0; f < poses.size(); ++f) {
    const auto joints = JointPositions(skeleton, poses[f]);
    arms_up |= joints[lw].z() > joints[head].z() && joints[rw].z() > joints[head].z();
    kick |= joints[rtoe].z() > 0.6;
    crouch |= joints[pelvis].z() < 0.65;
    // Facing -y at some point (the turn): the pelvis' forward axis.
    turned_back |= (poses[f].local_rotations[0] * Eigen::Vector3d::UnitY()).y() < -0.9;
    if (f % 10 == 0) {
      const RowMatrixX3d posed = SkinVertices(actor.mesh.vertices, actor.weights, skeleton, poses[f]);
      EXPECT_NEAR(posed.col(2).minCoeff(), 0.0, 0.04) << "frame " << f;
    }
  }
  EXPECT_TRUE(arms_up);
  EXPECT_TRUE(kick);
  EXPECT_TRUE(crouch);
  EXPECT_TRUE(turned_back);
}

TEST(StudioActor, BadOptionsThrow) {
  StudioActorOptions options;
  options.height_m = -1.0;
  EXPECT_THROW(BuildStudioActor(options), UsageError);
  options = {};
  options.target_triangles = 10;
  EXPECT_THROW(options.Check(), UsageError);
}

}  // namespace
}  // namespace confluent
