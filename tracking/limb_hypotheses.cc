#include "tracking/limb_hypotheses.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "tracking/body_model_impl.h"

namespace confluent {
namespace {

using Eigen::Vector3d;

using tracking_internal::kDeg;

// Upper-limb directions in the parent's rest-aligned frame (x lateral towards the limb's side,
// y forward, z up; mirrored for the right side), with the elbow/knee angles tried for each.
struct Placement {
  Vector3d direction;
  std::vector<double> bend_deg;
};

const std::vector<Placement>& ArmPlacements() {
  static const std::vector<Placement> placements = {
      {{0.17, 0.0, -1.0}, {5, 90}},    // down beside the body
      {{1.0, 0.0, 0.0}, {5, 90}},      // spread sideways
      {{0.35, 0.0, 1.0}, {5}},         // raised over the head
      {{0.2, 1.0, 0.0}, {5, 90}},      // forward
      {{0.2, 0.7, -0.7}, {5, 110}},    // forward and down, or guarding the chest
      {{0.3, 0.6, 0.75}, {5}},         // forward and up
      {{0.2, -0.5, -0.85}, {5}},       // back
      {{-0.3, 0.7, -0.6}, {60, 120}},  // across the body
  };
  return placements;
}

const std::vector<Placement>& LegPlacements() {
  static const std::vector<Placement> placements = {
      {{0.05, 0.0, -1.0}, {0, 90}},   // standing, or the shank lifted back
      {{0.05, 0.7, -0.7}, {0, 90}},   // thigh forward (a step, a knee raised)
      {{0.05, 1.0, -0.1}, {0, 90}},   // kicking forward, or knee up high
      {{0.7, 0.0, -0.7}, {0}},        // sideways
      {{0.05, -0.5, -0.85}, {0, 60}}, // back
  };
  return placements;
}

}  // namespace

const char* LimbName(Limb limb) {
  switch (limb) {
    case Limb::kLeftArm: return "left_arm";
    case Limb::kRightArm: return "right_arm";
    case Limb::kLeftLeg: return "left_leg";
    case Limb::kRightLeg: return "right_leg";
  }
  return "limb";
}

LimbChain LimbJoints(Limb limb) {
  switch (limb) {
    case Limb::kLeftArm: return {kJointLeftShoulder, kJointLeftElbow, kJointLeftWrist};
    case Limb::kRightArm: return {kJointRightShoulder, kJointRightElbow, kJointRightWrist};
    case Limb::kLeftLeg: return {kJointLeftHip, kJointLeftKnee, kJointLeftAnkle};
    case Limb::kRightLeg: return {kJointRightHip, kJointRightKnee, kJointRightAnkle};
  }
  return {kJointLeftShoulder, kJointLeftElbow, kJointLeftWrist};
}

std::vector<TemplatePose> LimbHypotheses(const BodyTemplate& body, const TemplatePose& pose, Limb limb) {
  const bool arm = IsArm(limb);
  const bool left = limb == Limb::kLeftArm || limb == Limb::kLeftLeg;
  const int root = LimbJoints(limb).root;
  const int middle = LimbJoints(limb).middle;
  // The body's left is -x: a direction "towards the limb's side" has x < 0 on the left.
  const double side = left ? -1.0 : 1.0;
  const auto& rest = body.generic_rest();
  const Vector3d rest_direction = (rest[middle] - rest[root]).normalized();
  const JointDof& bend_dof = body.dofs()[middle];
  std::vector<TemplatePose> hypotheses;
  for (const Placement& placement : arm ? ArmPlacements() : LegPlacements()) {
    const Vector3d direction =
        Vector3d(side * placement.direction.x(), placement.direction.y(), placement.direction.z()).normalized();
    const Eigen::AngleAxisd turn(Eigen::Quaterniond::FromTwoVectors(rest_direction, direction));
    for (double bend : placement.bend_deg) {
      TemplatePose hypothesis = pose;
      const Vector3d rotation = turn.angle() * turn.axis();
      hypothesis.dofs[root] = {rotation.x(), rotation.y(), rotation.z()};
      // Elbows flex forwards (positive); knees bend backwards (negative).
      hypothesis.dofs[middle] = {0.0, 0.0, 0.0};
      hypothesis.dofs[middle][0] = (arm ? 1.0 : -1.0) * bend * kDeg;
      hypothesis.dofs[middle][0] = std::clamp(hypothesis.dofs[middle][0], bend_dof.lower[0], bend_dof.upper[0]);
      body.ClampToLimits(&hypothesis);
      hypotheses.push_back(hypothesis);
    }
  }
  return hypotheses;
}

std::vector<TemplatePose> ArmTwistHypotheses(const BodyTemplate& body, const TemplatePose& pose, Limb arm,
                                             double bend_rad) {
  if (!IsArm(arm)) return {};
  const LimbChain chain = LimbJoints(arm);
  const auto& rest = body.generic_rest();
  const Vector3d bone = (rest[chain.middle] - rest[chain.root]).normalized();  // in the shoulder's rest frame
  const Eigen::Matrix3d rotation = tracking_internal::LocalRotation(body.dofs()[chain.root], pose.dofs[chain.root].data());
  const JointDof& elbow = body.dofs()[chain.middle];
  std::vector<TemplatePose> hypotheses;
  for (double twist_deg : {90.0, 180.0, -90.0}) {
    TemplatePose hypothesis = pose;
    // Turned after the shoulder's rotation about the rest bone: the upper arm points where it did.
    const Eigen::AngleAxisd turned(rotation * tracking_internal::AxisRotation(bone, twist_deg * kDeg));
    const Vector3d v = turned.angle() * turned.axis();
    hypothesis.dofs[chain.root] = {v.x(), v.y(), v.z()};
    hypothesis.dofs[chain.middle][0] =
        std::clamp(std::max(hypothesis.dofs[chain.middle][0], bend_rad), elbow.lower[0], elbow.upper[0]);
    body.ClampToLimits(&hypothesis);
    hypotheses.push_back(hypothesis);
  }
  return hypotheses;
}

std::vector<TemplatePose> HandBends(const BodyTemplate& body, const TemplatePose& pose, Limb arm,
                                    const std::vector<double>& flex_deg) {
  if (!IsArm(arm)) return {};
  const int wrist = LimbJoints(arm).end;
  std::vector<TemplatePose> bent;
  for (double flex : flex_deg) {
    TemplatePose hypothesis = pose;
    hypothesis.dofs[wrist][0] = flex * kDeg;
    hypothesis.dofs[wrist][1] = 0.0;
    body.ClampToLimits(&hypothesis);
    bent.push_back(hypothesis);
  }
  return bent;
}

}  // namespace confluent
