#include "tracking/body_template.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "core/bvh_io.h"
#include "core/mesh_io.h"
#include "core/mesh_ops.h"
#include "core/mesh_validation.h"
#include "studio/actor.h"
#include "tests/support/test_support.h"
#include "tracking/motion_io.h"

namespace confluent {
namespace {

// The faces of one segment as a mesh of its own.
Mesh SegmentMesh(const Mesh& mesh, int segment) {
  Mesh part;
  part.vertices = mesh.vertices;
  std::vector<Eigen::Vector3i> faces;
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (mesh.face_labels[f] == segment) faces.push_back(mesh.faces.row(f).transpose());
  part.faces.resize(faces.size(), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) part.faces.row(f) = faces[f].transpose();
  return part;
}

TemplatePose SomePose() {
  TemplatePose pose;
  pose.root_translation = Eigen::Vector3d(0.3, -0.2, 0.05);
  pose.root_rotation = Eigen::Vector3d(0.0, 0.1, 1.2);
  pose.dofs[kJointSpine] = {-0.2, 0.05, 0.1};
  pose.dofs[kJointLeftShoulder] = {0.3, 1.2, 0.1};
  pose.dofs[kJointLeftElbow] = {1.0, 0, 0};
  pose.dofs[kJointRightHip] = {0.8, 0.1, 0.0};
  pose.dofs[kJointRightKnee] = {-1.1, 0, 0};
  pose.dofs[kJointHead] = {0.2, 0.0, 0.4};
  return pose;
}

// The template and the studio actor stand on the same body: at 1.75 m with the arms 40 degrees
// from the vertical, the actor's skeleton has the template's joints, parents and rest pose.
TEST(BodyTemplate, StandsOnTheSameBodyAsTheStudioActor) {
  const BodyTemplate body;
  StudioActorOptions options;
  options.height_m = 1.75;
  options.arm_angle_deg = 40.0;
  const Skeleton skeleton = MakeStudioSkeleton(options);
  const std::vector<Eigen::Vector3d> rest = skeleton.RestPositions();
  ASSERT_EQ(rest.size(), static_cast<std::size_t>(kNumTemplateJoints));
  for (int j = 0; j < kNumTemplateJoints; ++j) {
    EXPECT_EQ(skeleton.joints[j].name, body.joint_names()[j]);
    EXPECT_EQ(skeleton.joints[j].parent, body.parents()[j]);
    EXPECT_LT((rest[j] - body.generic_rest()[j]).norm(), 1e-12) << body.joint_names()[j];
  }
}

TEST(BodyTemplate, HasFortyOneDofsAndTheBodysJointNames) {
  const BodyTemplate body;
  EXPECT_EQ(body.num_dofs(), 41);
  ASSERT_EQ(body.joint_names().size(), static_cast<std::size_t>(kNumTemplateJoints));
  EXPECT_EQ(body.joint_names()[kJointLeftElbow], "left_elbow");
  EXPECT_EQ(body.joint_names()[kJointRightToe], "right_toe");
}

TEST(BodyTemplate, EverySegmentIsWatertightAndOutward) {
  const BodyTemplate body;
  BodyShape shape;
  shape.length_scale[int(BodySegment::kLeftThigh)] = 1.2;
  shape.girth_scale[int(BodySegment::kUpperTorso)] = 0.8;
  for (const TemplatePose& pose : {TemplatePose(), SomePose()}) {
    const Mesh mesh = body.PosedMesh(shape, pose);
    ASSERT_TRUE(mesh.has_face_labels());
    EXPECT_GT(mesh.num_faces(), 2000);
    EXPECT_LT(mesh.num_faces(), 8000);
    for (int s = 0; s < kNumBodySegments; ++s) {
      const Mesh part = SegmentMesh(mesh, s);
      ASSERT_GT(part.num_faces(), 0) << BodySegmentName(s);
      // Edge test: every directed edge appears once and its opposite once.
      std::map<std::pair<int, int>, int> directed;
      for (int f = 0; f < part.num_faces(); ++f)
        for (int k = 0; k < 3; ++k) ++directed[{part.faces(f, k), part.faces(f, (k + 1) % 3)}];
      for (const auto& [edge, count] : directed) {
        EXPECT_EQ(count, 1) << BodySegmentName(s);
        EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << BodySegmentName(s);
      }
      EXPECT_GT(SignedVolume(part), 1e-5) << BodySegmentName(s);
    }
  }
}

TEST(BodyTemplate, ForwardKinematicsMovesSegmentsRigidly) {
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.6);
  const auto rest = body.RestPositions(shape);
  const TemplatePose pose = SomePose();
  const std::vector<Eigen::Vector3d> joints = body.JointPositions(shape, pose);
  // Bone lengths are preserved.
  for (int j = 1; j < kNumTemplateJoints; ++j) {
    const int p = body.parents()[j];
    EXPECT_NEAR((joints[j] - joints[p]).norm(), (rest[j] - rest[p]).norm(), 1e-9);
  }
  // The root moves by its translation at rest rotation.
  TemplatePose shifted;
  shifted.root_translation = Eigen::Vector3d(0.1, 0.2, 0.3);
  EXPECT_NEAR((body.JointPositions(shape, shifted)[kJointPelvis] - rest[kJointPelvis] - shifted.root_translation).norm(), 0, 1e-12);
  // A 90-degree knee flexion makes the shank perpendicular to the thigh.
  TemplatePose knee;
  knee.dofs[kJointLeftKnee] = {-M_PI / 2, 0, 0};
  const auto kj = body.JointPositions(shape, knee);
  const Eigen::Vector3d thigh = (kj[kJointLeftKnee] - kj[kJointLeftHip]).normalized();
  const Eigen::Vector3d shank = (kj[kJointLeftAnkle] - kj[kJointLeftKnee]).normalized();
  const double rest_angle = std::acos(((rest[kJointLeftKnee] - rest[kJointLeftHip]).normalized()).dot((rest[kJointLeftAnkle] - rest[kJointLeftKnee]).normalized()));
  EXPECT_NEAR(std::acos(thigh.dot(shank)), M_PI / 2, rest_angle + 1e-6);
  EXPECT_LT(shank.y(), 0.0);  // the shank folds backwards
  // Vertices within a segment keep their mutual distances.
  const Mesh a = body.PosedMesh(shape, TemplatePose()), b = body.PosedMesh(shape, pose);
  const int per_segment = a.num_vertices() / kNumBodySegments;
  for (int s = 0; s < kNumBodySegments; ++s)
    for (int k = 1; k < per_segment; k += 7) {
      const int v0 = s * per_segment, v1 = s * per_segment + k;
      EXPECT_NEAR((a.vertices.row(v0) - a.vertices.row(v1)).norm(), (b.vertices.row(v0) - b.vertices.row(v1)).norm(), 1e-9);
    }
}

TEST(BodyTemplate, ShapeScalesLengthsAndGirths) {
  const BodyTemplate body;
  BodyShape shape;
  const auto rest0 = body.RestPositions(shape);
  shape.length_scale[int(BodySegment::kRightForearm)] = 1.25;
  const auto rest1 = body.RestPositions(shape);
  EXPECT_NEAR((rest1[kJointRightWrist] - rest1[kJointRightElbow]).norm(), 1.25 * (rest0[kJointRightWrist] - rest0[kJointRightElbow]).norm(), 1e-12);
  EXPECT_NEAR((rest1[kJointLeftWrist] - rest1[kJointLeftElbow]).norm(), (rest0[kJointLeftWrist] - rest0[kJointLeftElbow]).norm(), 1e-12);
  BodyShape thick;
  thick.girth_scale[int(BodySegment::kHead)] = 1.5;
  thick.length_scale[int(BodySegment::kHead)] = 1.5;
  const double v0 = SignedVolume(SegmentMesh(body.PosedMesh(BodyShape(), TemplatePose()), int(BodySegment::kHead)));
  const double v1 = SignedVolume(SegmentMesh(body.PosedMesh(thick, TemplatePose()), int(BodySegment::kHead)));
  EXPECT_NEAR(v1 / v0, 1.5 * 1.5 * 1.5, 0.01);  // radii and caps scale with girth, the axis with length
}

// Cross-sections: depth scales the radii along e2 (front to back for the torso), taper the
// radii at end B (the upper torso's shoulder end), the offset moves the capsule along e2 and the
// bulge widens its middle; the joints stay where they are. A limb's axis stays on its bones.
TEST(BodyTemplate, CrossSectionsDeepenTaperAndMoveASegment) {
  const BodyTemplate body;
  const int chest = int(BodySegment::kUpperTorso);
  auto extent = [&](const BodyShape& shape) {  // the upper torso's box at rest
    const Mesh part = SegmentMesh(body.PosedMesh(shape, TemplatePose()), chest);
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
    for (int f = 0; f < part.num_faces(); ++f)
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d v = part.vertices.row(part.faces(f, k)).transpose();
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
      }
    return std::make_pair(lo, hi);
  };
  const auto [lo0, hi0] = extent(BodyShape());
  BodyShape deep;
  deep.depth_scale[chest] = 1.3;
  const auto [lo1, hi1] = extent(deep);
  EXPECT_NEAR((hi1.y() - lo1.y()) / (hi0.y() - lo0.y()), 1.3, 0.02);  // the template faces +y
  EXPECT_NEAR(hi1.x() - lo1.x(), hi0.x() - lo0.x(), 1e-9);
  BodyShape moved;
  moved.depth_offset[chest] = 0.2;
  const auto [lo2, hi2] = extent(moved);
  EXPECT_GT(lo2.y() - lo0.y(), 0.015);  // forwards by a fifth of its radius along y (about 2 cm)
  EXPECT_NEAR(lo2.y() - lo0.y(), hi2.y() - hi0.y(), 1e-9);
  BodyShape tapered;
  tapered.taper_scale[chest] = 1.2;  // end B, at the shoulders, wider
  const auto [lo3, hi3] = extent(tapered);
  EXPECT_NEAR((hi3.x() - lo3.x()) / (hi0.x() - lo0.x()), 1.2, 0.03);
  EXPECT_EQ(body.RestPositions(tapered), body.RestPositions(BodyShape()));
  EXPECT_EQ(body.RestPositions(moved), body.RestPositions(BodyShape()));
  // The bulge: the middle ring (s = 0.5) of the shank grows by the bulge, its ends do not.
  const int shank = int(BodySegment::kLeftShank);
  BodyShape calf;
  calf.mid_bulge[shank] = 0.25;
  calf.depth_offset[shank] = 0.3;  // ignored: not a torso segment
  const Mesh plain = body.PosedMesh(BodyShape(), TemplatePose()), bulged = body.PosedMesh(calf, TemplatePose());
  const int nv = static_cast<int>(body.mesh_coords().size());
  const Eigen::Vector3d knee = body.RestPositions(BodyShape())[kJointLeftKnee];
  const Eigen::Vector3d ankle = body.RestPositions(BodyShape())[kJointLeftAnkle];
  const Eigen::Vector3d axis = (ankle - knee).normalized();
  auto radial = [&](const Mesh& m, int v) {  // distance from the knee-ankle line
    const Eigen::Vector3d p = m.vertices.row(shank * nv + v).transpose() - knee;
    return (p - axis * axis.dot(p)).norm();
  };
  int middle = 0, ends = 0;
  for (int v = 0; v < nv; ++v) {
    const SurfaceCoord& sc = body.mesh_coords()[v];
    if (sc.c != 0.0) continue;
    if (sc.s == 0.5) {
      EXPECT_NEAR(radial(bulged, v) / radial(plain, v), 1.25, 1e-6);
      ++middle;
    } else if (sc.s == 0.0 || sc.s == 1.0) {
      EXPECT_NEAR(radial(bulged, v), radial(plain, v), 1e-9);
      ++ends;
    }
  }
  EXPECT_GT(middle, 0);
  EXPECT_GT(ends, 0);
}

TEST(BodyTemplate, ExportsPlyWithSegmentLabels) {
  const testing::TempDir dir;
  const BodyTemplate body;
  const Mesh mesh = body.PosedMesh(BodyShape(), SomePose());
  WriteMesh(dir / "t.ply", mesh);
  const Mesh back = ReadMesh(dir / "t.ply");
  ASSERT_EQ(back.num_faces(), mesh.num_faces());
  ASSERT_TRUE(back.has_face_labels());
  for (int f = 0; f < mesh.num_faces(); f += 97) EXPECT_EQ(back.face_labels[f], mesh.face_labels[f]);
  EXPECT_NEAR((back.vertices - mesh.vertices).cwiseAbs().maxCoeff(), 0.0, 1e-5);
  WriteMesh(dir / "t.obj", mesh);
  EXPECT_EQ(ReadMesh(dir / "t.obj").num_faces(), mesh.num_faces());
}

TEST(BodyTemplate, BvhRoundTripsThroughOurReader) {
  const testing::TempDir dir;
  const BodyTemplate body;
  const BodyShape shape = BodyShape::Uniform(1.8);
  const Skeleton skeleton = body.MakeSkeleton(shape);
  std::vector<Pose> poses = {body.ToPose(TemplatePose()), body.ToPose(SomePose())};
  WriteBvh(dir / "m.bvh", skeleton, poses, 0.04);
  BvhReadOptions options;
  options.scale = 0.01;
  options.y_up_to_z_up = true;
  const BvhMotion motion = ReadBvh(dir / "m.bvh", options);
  ASSERT_EQ(motion.frames.size(), poses.size());
  ASSERT_EQ(motion.skeleton.size(), skeleton.size());
  EXPECT_NEAR(motion.frame_time_s, 0.04, 1e-9);
  for (std::size_t f = 0; f < poses.size(); ++f) {
    const auto expected = JointPositions(skeleton, poses[f]);
    const auto actual = JointPositions(motion.skeleton, motion.frames[f]);
    for (int j = 0; j < skeleton.size(); ++j) EXPECT_NEAR((expected[j] - actual[j]).norm(), 0.0, 1e-4) << j;
  }
}

}  // namespace
}  // namespace confluent
