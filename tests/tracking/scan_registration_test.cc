// Registration of the template to scans (issue 7): known shape and pose recovered from a
// differently tessellated template-like scan, in any orientation; non-human scans refused;
// correspondence placement on the (low-resolution) studio actor; the registration's JSON.

#include "tracking/scan_registration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <set>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/body_segments.h"
#include "core/error.h"
#include "core/mesh_ops.h"
#include "core/skinning.h"
#include "deform/correspondence_placement.h"
#include "studio/actor.h"
#include "studio/motion.h"
#include "tests/deform/test_geometry.h"
#include "tests/support/test_support.h"
#include "tracking/pose_from_joints.h"

namespace confluent {
namespace {

using Eigen::Vector3d;

BodyShape KnownShape() {
  BodyShape shape = BodyShape::Uniform(1.68);
  shape.length_scale[int(BodySegment::kLeftThigh)] *= 1.06;
  shape.length_scale[int(BodySegment::kRightThigh)] *= 1.06;
  shape.girth_scale[int(BodySegment::kUpperTorso)] *= 1.1;
  shape.girth_scale[int(BodySegment::kLowerTorso)] *= 1.1;
  return shape;
}

TemplatePose KnownPose() {
  TemplatePose pose;
  pose.root_translation = Vector3d(0.4, -0.3, 0.0);
  pose.root_rotation = Vector3d(0, 0, 0.6);
  pose.dofs[kJointLeftElbow] = {0.5, 0, 0};
  pose.dofs[kJointRightElbow] = {0.3, 0, 0};
  pose.dofs[kJointLeftHip] = {0.25, 0, 0};
  pose.dofs[kJointLeftKnee] = {-0.4, 0, 0};
  pose.dofs[kJointSpine] = {0.1, 0, 0.1};
  return pose;
}

// A template-like scan: the template with a finer tessellation (20 steps around instead of
// 12), shape and pose known, moved by `scan_from_world`.
Mesh TemplateLikeScan(const Eigen::Isometry3d& scan_from_world) {
  const BodyTemplate fine(20);
  Mesh scan = fine.PosedMesh(KnownShape(), KnownPose());
  for (int v = 0; v < scan.num_vertices(); ++v)
    scan.vertices.row(v) = (scan_from_world * Vector3d(scan.vertices.row(v).transpose())).transpose();
  scan.face_labels.clear();
  return scan;
}

// Mean distance between the registered and the true joints (scan frame).
double MeanJointError(const BodyTemplate& body, const ScanRegistration& registration, const Eigen::Isometry3d& scan_from_world) {
  const auto fitted = body.JointPositions(registration.shape, registration.pose);
  const auto truth = body.JointPositions(KnownShape(), KnownPose());
  double sum = 0;
  int n = 0;
  for (int j = 0; j < kNumTemplateJoints; ++j) {
    if (j == kJointHeadEnd || j == kJointLeftHandEnd || j == kJointRightHandEnd || j == kJointLeftToe || j == kJointRightToe) continue;
    sum += (fitted[j] - scan_from_world * truth[j]).norm();
    ++n;
  }
  return sum / n;
}

TEST(ScanRegistration, RecoversKnownShapeAndPoseOfATemplateLikeScan) {
  const BodyTemplate body;
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const ScanRegistration registration = RegisterTemplateToScan(body, TemplateLikeScan(identity));
  EXPECT_LT(MeanJointError(body, registration, identity), 0.02);
  EXPECT_LT(registration.trimmed_rms_residual_m, 0.01);
  EXPECT_NEAR(registration.shape.length_scale[int(BodySegment::kLeftThigh)], KnownShape().length_scale[int(BodySegment::kLeftThigh)], 0.06);
  EXPECT_NEAR(registration.up_in_scan.z(), 1.0, 0.02);
  EXPECT_DOUBLE_EQ(registration.metres_per_unit, 1.0);
}

TEST(ScanRegistration, UpsideDownScanIsReorientedAndSaysSo) {
  const BodyTemplate body;
  Eigen::Isometry3d flip = Eigen::Isometry3d::Identity();
  flip.linear() = Eigen::AngleAxisd(M_PI, Vector3d::UnitX()).toRotationMatrix();
  flip.translation() = Vector3d(0, 0, 2.0);
  const ScanRegistration registration = RegisterTemplateToScan(body, TemplateLikeScan(flip));
  EXPECT_LT(MeanJointError(body, registration, flip), 0.02);
  EXPECT_LT(registration.up_in_scan.z(), -0.95);
  bool said = false;
  for (const std::string& w : registration.warnings) said = said || w.find("upside down") != std::string::npos;
  EXPECT_TRUE(said);
  // Refused when re-orientation is not allowed.
  ScanRegistrationOptions strict;
  strict.allow_reorientation = false;
  EXPECT_THROW(RegisterTemplateToScan(body, TemplateLikeScan(flip), strict, "flipped.ply"), InputError);
}

TEST(ScanRegistration, ScanLyingOnItsSideInDecimetresIsHandled) {
  const BodyTemplate body;
  Eigen::Isometry3d side = Eigen::Isometry3d::Identity();
  side.linear() = 10.0 * Eigen::AngleAxisd(-M_PI / 2, Vector3d::UnitX()).toRotationMatrix();  // Y up, decimetres
  const ScanRegistration registration = RegisterTemplateToScan(body, TemplateLikeScan(side));
  EXPECT_DOUBLE_EQ(registration.metres_per_unit, 0.1);
  EXPECT_GT(registration.up_in_scan.y(), 0.95);
  EXPECT_LT(MeanJointError(body, registration, side), 0.2);  // 2 cm in decimetres
}

TEST(ScanRegistration, TPoseScanWithHolesAndASeparateHairPiece) {
  const BodyTemplate body;
  const BodyTemplate fine(20);
  // T-pose: upper arms horizontal (rotation about the forward axis), elbows straight.
  TemplatePose pose;
  pose.root_translation = Vector3d(-0.2, 0.1, 0.0);
  pose.dofs[kJointLeftShoulder] = {0.0, 50.0 * M_PI / 180.0, 0.0};
  pose.dofs[kJointRightShoulder] = {0.0, -50.0 * M_PI / 180.0, 0.0};
  const BodyShape shape = BodyShape::Uniform(1.8);
  const Mesh posed = fine.PosedMesh(shape, pose);
  const auto truth = fine.JointPositions(shape, pose);
  ASSERT_NEAR(truth[kJointLeftElbow].z(), truth[kJointLeftShoulder].z(), 0.03);  // really a T-pose
  // Holes: drop every face whose centroid lies in a band around the belly or on the left shin.
  Mesh scan;
  scan.vertices = posed.vertices;
  std::vector<Eigen::Vector3i> faces;
  for (int f = 0; f < posed.num_faces(); ++f) {
    const Vector3d c = (posed.vertices.row(posed.faces(f, 0)) + posed.vertices.row(posed.faces(f, 1)) +
                        posed.vertices.row(posed.faces(f, 2))).transpose() / 3.0;
    const bool belly = c.z() > 1.05 && c.z() < 1.1 && c.y() > 0.0;
    const bool shin = c.x() < 0 && c.z() > 0.25 && c.z() < 0.3;
    if (!belly && !shin) faces.push_back(posed.faces.row(f).transpose());
  }
  // A separate hair piece: a flat box on top of the head.
  const Mesh hair = MakeBox(truth[kJointHeadEnd] + Vector3d(-0.09, -0.1, -0.02), truth[kJointHeadEnd] + Vector3d(0.09, 0.06, 0.03));
  const int offset = scan.num_vertices();
  scan.vertices.conservativeResize(offset + hair.num_vertices(), 3);
  scan.vertices.bottomRows(hair.num_vertices()) = hair.vertices;
  for (int f = 0; f < hair.num_faces(); ++f) faces.push_back(hair.faces.row(f).transpose() + Eigen::Vector3i::Constant(offset));
  ASSERT_LT(static_cast<int>(faces.size()), posed.num_faces());
  scan.faces.resize(faces.size(), 3);
  for (std::size_t f = 0; f < faces.size(); ++f) scan.faces.row(f) = faces[f].transpose();

  const ScanRegistration registration = RegisterTemplateToScan(body, scan);
  const auto fitted = body.JointPositions(registration.shape, registration.pose);
  for (int j : {int(kJointLeftElbow), int(kJointRightElbow), int(kJointLeftWrist), int(kJointRightWrist), int(kJointLeftKnee), int(kJointHead)})
    EXPECT_LT((fitted[j] - truth[j]).norm(), 0.04) << body.joint_names()[j];
}

// The studio actor as posed at the built-in performance's first frame (arms a little forward,
// weight on one leg), turned to face four ways: front and back look alike to a rigid fit of the
// whole body, and the registration must still face the way the actor faces, left on left.
TEST(ScanRegistration, FacesTheWayTheActorFacesNotTheOtherWay) {
  StudioActorOptions actor_options;
  actor_options.target_triangles = 12000;
  const StudioActor actor = BuildStudioActor(actor_options);
  StudioMotionOptions motion;
  motion.num_frames = 1;
  const Pose first = DefaultPerformance(actor.skeleton, motion).front();
  const auto joints = WorldFromJoint(actor.skeleton, first);
  const BodyTemplate body;
  for (int quarter = 0; quarter < 4; ++quarter) {
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(quarter * M_PI / 2, Vector3d::UnitZ()).toRotationMatrix();
    Mesh scan = actor.mesh;
    scan.vertices = SkinVertices(actor.mesh.vertices, actor.weights, actor.skeleton, first, SkinningMethod::kDualQuaternion) *
                    turn.transpose();
    const ScanRegistration registration = RegisterTemplateToScan(body, scan);
    const auto fitted = body.JointPositions(registration.shape, registration.pose);
    for (int j : {int(kJointLeftHip), int(kJointRightHip), int(kJointLeftShoulder), int(kJointRightShoulder),
                  int(kJointLeftAnkle), int(kJointRightAnkle), int(kJointHead)})
      EXPECT_LT((fitted[j] - turn * joints[j].translation()).norm(), 0.05)
          << body.joint_names()[j] << ", actor turned " << 90 * quarter << " degrees";
  }
}

TEST(ScanRegistration, SphereIsRefusedWithTheResidual) {
  const BodyTemplate body;
  const Mesh sphere = MakeUvSphere(0.8, 24, 48);
  try {
    RegisterTemplateToScan(body, sphere, {}, "sphere.ply");
    FAIL() << "a sphere was accepted as a human scan";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("sphere.ply"), std::string::npos) << what;
    EXPECT_NE(what.find("residual"), std::string::npos) << what;
  }
}

TEST(ScanRegistration, RegistrationRoundTripsThroughCorrespondencesJson) {
  const BodyTemplate body;
  testing::TempDir dir;
  const std::string path = dir / "c.json";
  std::ofstream(path) << "{\"pairs\": [{\"template_triangle\": 1, \"scan_triangle\": 2}]}";
  EXPECT_THROW(ReadTemplateRegistration(path, body), InputError);
  ScanRegistration registration;
  registration.shape = KnownShape();
  registration.pose = KnownPose();
  registration.rms_residual_m = 0.012;
  WriteTemplateRegistration(path, body, registration);
  const ScanRegistration back = ReadTemplateRegistration(path, body);
  for (int s = 0; s < kNumBodySegments; ++s) {
    EXPECT_DOUBLE_EQ(back.shape.length_scale[s], registration.shape.length_scale[s]);
    EXPECT_DOUBLE_EQ(back.shape.girth_scale[s], registration.shape.girth_scale[s]);
  }
  EXPECT_TRUE(back.pose.root_translation.isApprox(registration.pose.root_translation));
  EXPECT_DOUBLE_EQ(back.pose.dofs[kJointLeftElbow][0], 0.5);
  EXPECT_DOUBLE_EQ(back.rms_residual_m, 0.012);
  EXPECT_FALSE(back.first_tracked_pose);

  // With the first tracked pose of a scan in that frame's pose (the first frames' seam).
  TemplatePose first = KnownPose();
  first.dofs[kJointLeftElbow][0] = 0.7;
  first.root_rotation = Vector3d(0.0, 0.1, 0.3);
  registration.first_tracked_pose = first;
  WriteTemplateRegistration(path, body, registration);
  const ScanRegistration seam = ReadTemplateRegistration(path, body);
  ASSERT_TRUE(seam.first_tracked_pose);
  EXPECT_DOUBLE_EQ(seam.first_tracked_pose->dofs[kJointLeftElbow][0], 0.7);
  EXPECT_TRUE(seam.first_tracked_pose->root_rotation.isApprox(first.root_rotation));
  EXPECT_DOUBLE_EQ(seam.pose.dofs[kJointLeftElbow][0], 0.5);
}

TEST(ScanRegistration, MalformedFirstTrackedPoseIsNamed) {
  const BodyTemplate body;
  testing::TempDir dir;
  const std::string path = dir / "c.json";
  std::ofstream(path) << "{\"pairs\": []}";
  EXPECT_FALSE(HasTemplateRegistration(path));
  ScanRegistration registration;
  registration.pose = KnownPose();
  WriteTemplateRegistration(path, body, registration);
  EXPECT_TRUE(HasTemplateRegistration(path));
  // A hand edit: the elbow of the first tracked pose given one angle too many.
  std::ifstream in(path);
  nlohmann::json root = nlohmann::json::parse(in);
  root["template_registration"]["first_tracked_pose"] = root["template_registration"]["pose"];
  root["template_registration"]["first_tracked_pose"]["joint_angles"]["left_elbow"] = {0.1, 0.2};
  std::ofstream(path) << root.dump();
  try {
    ReadTemplateRegistration(path, body);
    ADD_FAILURE() << "a malformed first_tracked_pose was read";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("c.json"), std::string::npos) << what;
    EXPECT_NE(what.find("first_tracked_pose.joint_angles: left_elbow"), std::string::npos) << what;
  }
  std::ofstream(path) << "{\"pairs\": [";
  EXPECT_THROW(HasTemplateRegistration(path), InputError);
}

TEST(PoseFromJoints, RecoversAPoseFromItsJointsAndRotations) {
  const BodyTemplate body;
  const BodyShape shape = KnownShape();
  TemplatePose truth = KnownPose();
  truth.dofs[kJointHead] = {0.1, 0.0, 0.5};  // a head turn: only observable through the rotations
  const std::vector<Vector3d> joints = body.JointPositions(shape, truth);
  const auto world = WorldFromJoint(body.MakeSkeleton(shape), body.ToPose(truth));
  std::vector<Eigen::Quaterniond> rotations;
  for (const auto& t : world) rotations.emplace_back(t.linear());
  const TemplatePose fitted = FitPoseToJoints(body, shape, joints, &rotations, TemplatePose());
  const std::vector<Vector3d> again = body.JointPositions(shape, fitted);
  for (int j = 0; j < kNumTemplateJoints; ++j) EXPECT_LT((again[j] - joints[j]).norm(), 1e-4) << j;
  EXPECT_NEAR(fitted.dofs[kJointHead][2], 0.5, 1e-3);
}

// The (low-resolution) studio actor and the template registered to it: its joints and its
// posed mesh.
struct RegisteredActor {
  StudioActor actor;
  ScanRegistration registration;
  std::vector<Vector3d> joints;
  Mesh template_mesh;
};

RegisteredActor RegisterTemplateToStudioActor() {
  StudioActorOptions actor_options;
  actor_options.target_triangles = 12000;
  RegisteredActor result{BuildStudioActor(actor_options), {}, {}, {}};
  const BodyTemplate body;
  result.registration = RegisterTemplateToScan(body, result.actor.mesh);
  result.joints = body.JointPositions(result.registration.shape, result.registration.pose);
  result.template_mesh = body.PosedMesh(result.registration.shape, result.registration.pose);
  return result;
}

TEST(CorrespondencePlacement, StudioActorGets140To220PairsOnAll16Segments) {
  const RegisteredActor registered = RegisterTemplateToStudioActor();
  const StudioActor& actor = registered.actor;
  const auto& joints = registered.joints;
  const Mesh& template_mesh = registered.template_mesh;
  EXPECT_LT(registered.registration.trimmed_rms_residual_m, 0.02);
  // The studio actor's rest skeleton is the template's generic one: joints should agree.
  const auto truth = actor.skeleton.RestPositions();
  EXPECT_LT((joints[kJointLeftElbow] - truth[kJointLeftElbow]).norm(), 0.05);
  EXPECT_LT((joints[kJointRightKnee] - truth[kJointRightKnee]).norm(), 0.05);

  CorrespondencePlacementOptions options;
  options.joint_positions = joints;
  const Correspondences pairs = PlaceCorrespondences(template_mesh, actor.mesh, options);
  EXPECT_GE(pairs.pairs.size(), 140u);
  EXPECT_LE(pairs.pairs.size(), 220u);
  ValidateCorrespondences(pairs, template_mesh.num_faces(), actor.mesh.num_faces(), "placed");
  std::set<std::string> segments;
  const RowMatrixX3d template_normals = FaceNormals(template_mesh), scan_normals = FaceNormals(actor.mesh);
  for (const CorrespondencePair& p : pairs.pairs) {
    segments.insert(p.segment);
    EXPECT_EQ(BodySegmentName(template_mesh.face_labels[p.template_triangle]), p.segment);
    EXPECT_GT(template_normals.row(p.template_triangle).dot(scan_normals.row(p.scan_triangle)), 0.5);
    // The scan triangle lies on the same body part: its label in the actor agrees.
    const int scan_label = actor.mesh.face_labels[p.scan_triangle];
    const int template_label = template_mesh.face_labels[p.template_triangle];
    const bool left_t = BodySegmentName(template_label).rfind("left", 0) == 0;
    const bool right_s = BodySegmentName(scan_label).rfind("right", 0) == 0;
    EXPECT_FALSE(left_t && right_s) << p.segment << " paired with " << BodySegmentName(scan_label);
  }
  EXPECT_EQ(segments.size(), static_cast<std::size_t>(kNumBodySegments));
  // Markers keep the clearance from the joints at the ends of the limbs (along the limb).
  const Vector3d elbow = joints[kJointLeftElbow], shoulder = joints[kJointLeftShoulder];
  const Vector3d axis = (elbow - shoulder).normalized();
  for (const CorrespondencePair& p : pairs.pairs) {
    if (p.segment != "left_upper_arm") continue;
    const Vector3d c = testing::FaceCentroid(template_mesh, p.template_triangle);
    EXPECT_GE(std::abs((c - elbow).dot(axis)), options.joint_clearance_m - 1e-9);
  }
  // A partial manual file is kept and completed.
  Correspondences manual;
  manual.pairs.push_back(pairs.pairs[0]);
  manual.pairs[0].segment.clear();
  const Correspondences completed = PlaceCorrespondences(template_mesh, actor.mesh, options, &manual);
  ASSERT_GE(completed.pairs.size(), 140u);
  EXPECT_EQ(completed.pairs[0].template_triangle, pairs.pairs[0].template_triangle);
  EXPECT_EQ(completed.pairs[0].segment, pairs.pairs[0].segment);
}

// The lower torso's upper ring of markers lies on the belly and the lower back, between the hips
// and the waist: the template's lower torso reaches into the upper torso, and a ring placed on
// that buried cap found no scan surface (one marker of eight, the rest between the legs), so the
// pelvis turned with the thighs and the chest in the transfer. No torso marker is nearer the spine
// joint than twice the clearance.
TEST(CorrespondencePlacement, TheLowerTorsoIsHeldAboveTheHipsFrontAndBack) {
  const RegisteredActor registered = RegisterTemplateToStudioActor();
  const auto& joints = registered.joints;
  const Mesh& template_mesh = registered.template_mesh;
  CorrespondencePlacementOptions options;
  SetBodyJoints(joints, &options);
  const Correspondences pairs = PlaceCorrespondences(template_mesh, registered.actor.mesh, options);
  const Vector3d hips = 0.5 * (joints[kJointLeftHip] + joints[kJointRightHip]);
  const Vector3d up = (joints[kJointSpine] - hips).normalized();
  const Vector3d forward = up.cross(joints[kJointLeftHip] - joints[kJointRightHip]).normalized();
  const double waist = (joints[kJointSpine] - hips).dot(up);
  int front = 0, back = 0, between_the_legs = 0;
  for (const CorrespondencePair& p : pairs.pairs) {
    if (p.segment != "lower_torso" && p.segment != "upper_torso") continue;
    const Vector3d c = testing::FaceCentroid(template_mesh, p.template_triangle);
    // The spine's clearance is twice a limb joint's, on both torso parts (5 mm spared: the
    // placement measures along the trunk's axis, head to pelvis, not hips to spine).
    EXPECT_GE(std::abs((c - joints[kJointSpine]).dot(up)), 2.0 * options.joint_clearance_m - 0.005) << p.segment;
    if (p.segment != "lower_torso") continue;
    const double height = (c - hips).dot(up);
    if (height < 0) {
      ++between_the_legs;
      continue;
    }
    EXPECT_LT(height, waist) << "a lower torso marker above the spine joint";
    ((c - hips).dot(forward) > 0 ? front : back) += 1;
  }
  EXPECT_GE(front, 3) << "back " << back << ", between the legs " << between_the_legs;
  EXPECT_GE(back, 3) << "front " << front << ", between the legs " << between_the_legs;
}

}  // namespace
}  // namespace confluent
