#include "tracking/body_template.h"

#include <algorithm>
#include <cmath>

#include "tracking/body_model_impl.h"

namespace confluent {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
namespace ti = tracking_internal;

using ti::kDeg;

JointDof Ball(double x_lo, double x_hi, double y_lo, double y_hi, double z_lo, double z_hi) {
  JointDof d;
  d.type = JointType::kBall;
  d.lower = {x_lo * kDeg, y_lo * kDeg, z_lo * kDeg};
  d.upper = {x_hi * kDeg, y_hi * kDeg, z_hi * kDeg};
  return d;
}

JointDof Hinge(const Vector3d& axis, double lo, double hi) {
  JointDof d;
  d.type = JointType::kHinge;
  d.axes[0] = axis.normalized();
  d.lower = {lo * kDeg, 0, 0};
  d.upper = {hi * kDeg, 0, 0};
  return d;
}

JointDof Hinge2(const Vector3d& a0, double lo0, double hi0, const Vector3d& a1, double lo1, double hi1) {
  JointDof d;
  d.type = JointType::kHinge2;
  d.axes = {a0.normalized(), a1.normalized()};
  d.lower = {lo0 * kDeg, lo1 * kDeg, 0};
  d.upper = {hi0 * kDeg, hi1 * kDeg, 0};
  return d;
}

// The pull of a hand bent out of its plane towards straight. Per radian; 5 left the punch's
// right wrist 7.7 cm off at worst, 15 1.9 cm.
constexpr double kWristPalmBendRestWeight = 15.0;
constexpr double kWristPalmBendRestFade = 10 * kDeg;

}  // namespace

BodyShape BodyShape::Uniform(double height_m) {
  BodyShape shape;
  shape.length_scale.fill(height_m / 1.75);
  shape.girth_scale.fill(height_m / 1.75);
  return shape;
}

BodyTemplate::BodyTemplate(int longitudes) {
  joint_names_ = BodyJointNames();
  parents_ = BodyJointParents();
  // Generic adult proportions (1.75 m), A-pose with the arms 40 degrees from the vertical.
  generic_rest_ = BodyRestPositions(40.0 * kDeg);
  const auto& r = generic_rest_;
  // Which segment's length scale stretches each bone.
  const int S[kNumTemplateJoints] = {-1,
                                     int(BodySegment::kLowerTorso), int(BodySegment::kUpperTorso),
                                     int(BodySegment::kUpperTorso), int(BodySegment::kNeck), int(BodySegment::kHead),
                                     int(BodySegment::kUpperTorso), int(BodySegment::kLeftUpperArm),
                                     int(BodySegment::kLeftForearm), int(BodySegment::kLeftHand),
                                     int(BodySegment::kUpperTorso), int(BodySegment::kRightUpperArm),
                                     int(BodySegment::kRightForearm), int(BodySegment::kRightHand),
                                     int(BodySegment::kLowerTorso), int(BodySegment::kLeftThigh),
                                     int(BodySegment::kLeftShank), int(BodySegment::kLeftFoot),
                                     int(BodySegment::kLowerTorso), int(BodySegment::kRightThigh),
                                     int(BodySegment::kRightShank), int(BodySegment::kRightFoot)};
  std::copy(S, S + kNumTemplateJoints, offset_segment_.begin());

  // Degrees of freedom and anatomical limits (degrees, on the rotation-vector components in
  // the parent's rest-aligned frame: x = lateral axis, y = forward axis, z = up).
  dofs_[kJointSpine] = Ball(-50, 35, -35, 35, -45, 45);
  dofs_[kJointChest] = Ball(-35, 30, -30, 30, -45, 45);
  // The cervical spine bends at its base too: without it a head bowed or raised sits where an
  // upright neck puts it (the head joint 2-5 cm off on performances that look up or down). No
  // twist: the head's own turns it, and the two would trade it from frame to frame. The ranges
  // reach a head thrown back and to the side (a jumper's at take-off; at 35 and 25 degrees here,
  // 50 and 45 at the head, the template lost that head for 9 frames, 4-7 cm off).
  dofs_[kJointNeck] = Hinge2(Vector3d::UnitX(), -45, 45, Vector3d::UnitY(), -35, 35);
  dofs_[kJointHead] = Ball(-60, 60, -55, 55, -80, 80);
  for (int side = 0; side < 2; ++side) {
    const int shoulder = side == 0 ? kJointLeftShoulder : kJointRightShoulder;
    dofs_[shoulder] = Ball(-170, 170, -170, 170, -170, 170);
    const Vector3d upper_dir = (r[shoulder + 1] - r[shoulder]).normalized();
    const Vector3d hinge = upper_dir.cross(Vector3d::UnitY()).normalized();  // flexion moves the forearm forwards
    dofs_[shoulder + 1] = Hinge(hinge, -5, 155);
    // The wrist bends the hand in its own plane about the elbow's hinge (the rest hand is held
    // thumb forwards: radial and ulnar deviation, given a wide range) and out of it, towards the
    // palm or its back (flexion and extension, given a narrow one). A hand flat on the floor
    // bends 90 degrees out of its plane (the suite's cartwheel), and at 35 the hand's end stays
    // 7-18 cm off there; at 85 the cartwheel's and a jumper's hands follow. The first frame's fits
    // keep 35 (TrackerOptions::first_frame_wrist_palm_bend_rad): there the wide range folded the
    // Indian dance's right forearm for 6 frames and fitted Bandai's arms 3% shorter (bench/SUITE.md,
    // session 62).
    const Vector3d palm_axis = hinge.cross(upper_dir).normalized();
    dofs_[shoulder + 2] = Hinge2(hinge, -75, 75, palm_axis, -85, 85);
    // The silhouettes hardly see that bend (a hand is a few pixels wide at the fit's scale), and
    // the fit trades it for a turned forearm (Bandai's punch: elbows 2.5-3 cm off, straight
    // hands bent). A pull towards a straight hand, with the limits kept for real bends.
    dofs_[shoulder + 2].rest_weight[1] = kWristPalmBendRestWeight;
    dofs_[shoulder + 2].rest_fade_rad = kWristPalmBendRestFade;
    const int hip = side == 0 ? kJointLeftHip : kJointRightHip;
    dofs_[hip] = Ball(-40, 135, -55, 55, -60, 60);
    dofs_[hip + 1] = Hinge(Vector3d::UnitX(), -160, 5);
    dofs_[hip + 2] = Hinge2(Vector3d::UnitX(), -50, 50, Vector3d::UnitY(), -30, 30);
  }

  // Segment capsules (generic radii in metres).
  auto seg = [&](BodySegment s, int joint, int ja, Vector3d oa, int jb, Vector3d ob, Vector2d ra, Vector2d rb, double ca,
                 double cb, Vector3d e1) {
    segments_[int(s)] = SegmentShape{joint, ja, jb, oa, ob, ra, rb, ca, cb, e1};
  };
  const Vector3d X = Vector3d::UnitX(), Y = Vector3d::UnitY(), O = Vector3d::Zero();
  seg(BodySegment::kHead, kJointHead, kJointHead, Vector3d(0, 0.01, 0.06), kJointHead, Vector3d(0, 0.01, 0.12),
      Vector2d(0.08, 0.097), Vector2d(0.078, 0.095), 0.065, 0.07, X);
  seg(BodySegment::kNeck, kJointNeck, kJointNeck, Vector3d(0, 0, -0.03), kJointHead, Vector3d(0, 0, 0.01), Vector2d(0.055, 0.057),
      Vector2d(0.052, 0.054), 0.04, 0.04, X);
  seg(BodySegment::kUpperTorso, kJointChest, kJointSpine, O, kJointNeck, Vector3d(0, 0, -0.035), Vector2d(0.145, 0.095),
      Vector2d(0.175, 0.1), 0.08, 0.07, X);
  seg(BodySegment::kLowerTorso, kJointPelvis, kJointPelvis, Vector3d(0, 0, -0.07), kJointSpine, O, Vector2d(0.16, 0.105),
      Vector2d(0.145, 0.095), 0.09, 0.06, X);
  for (int side = 0; side < 2; ++side) {
    const int shoulder = side == 0 ? kJointLeftShoulder : kJointRightShoulder;
    const int hip = side == 0 ? kJointLeftHip : kJointRightHip;
    const BodySegment upper = side == 0 ? BodySegment::kLeftUpperArm : BodySegment::kRightUpperArm;
    const BodySegment fore = side == 0 ? BodySegment::kLeftForearm : BodySegment::kRightForearm;
    const BodySegment hand = side == 0 ? BodySegment::kLeftHand : BodySegment::kRightHand;
    const BodySegment thigh = side == 0 ? BodySegment::kLeftThigh : BodySegment::kRightThigh;
    const BodySegment shank = side == 0 ? BodySegment::kLeftShank : BodySegment::kRightShank;
    const BodySegment foot = side == 0 ? BodySegment::kLeftFoot : BodySegment::kRightFoot;
    const Vector3d hand_dir = (r[shoulder + 3] - r[shoulder + 2]).normalized();
    seg(upper, shoulder, shoulder, O, shoulder + 1, O, Vector2d(0.055, 0.055), Vector2d(0.042, 0.043), 0.05, 0.04, Y);
    seg(fore, shoulder + 1, shoulder + 1, O, shoulder + 2, O, Vector2d(0.042, 0.043), Vector2d(0.028, 0.024), 0.04, 0.025, Y);
    seg(hand, shoulder + 2, shoulder + 2, 0.02 * hand_dir, shoulder + 3, -0.035 * hand_dir, Vector2d(0.038, 0.017),
        Vector2d(0.04, 0.013), 0.02, 0.03, Y);
    seg(thigh, hip, hip, Vector3d(0, 0, 0.02), hip + 1, O, Vector2d(0.088, 0.09), Vector2d(0.056, 0.058), 0.08, 0.055, X);
    seg(shank, hip + 1, hip + 1, O, hip + 2, O, Vector2d(0.053, 0.055), Vector2d(0.036, 0.038), 0.05, 0.035, X);
    seg(foot, hip + 2, hip + 2, Vector3d(0, -0.035, -0.04), hip + 3, Vector3d(0, -0.025, 0.017),
        Vector2d(0.038, 0.04), Vector2d(0.045, 0.032), 0.04, 0.045, X);
  }

  // Surface meshing: a pole, cap rings, body rings, cap rings, a pole.
  longitudes = std::max(longitudes, 6);
  const int cap_rings = 3, body_bands = 4;
  struct Ring { double s, c, rho; };
  std::vector<Ring> rings;
  for (int i = 1; i < cap_rings; ++i) {
    const double phi = 0.5 * M_PI * i / cap_rings;
    rings.push_back({0.0, -std::cos(phi), std::sin(phi)});
  }
  for (int j = 0; j <= body_bands; ++j) rings.push_back({double(j) / body_bands, 0.0, 1.0});
  for (int i = cap_rings - 1; i >= 1; --i) {
    const double phi = 0.5 * M_PI * i / cap_rings;
    rings.push_back({1.0, std::cos(phi), std::sin(phi)});
  }
  // The fit measures the analytic ellipses; each ring is drawn as the polygon of the same area
  // (not the inscribed one, 4.5% smaller at 12 longitudes), so the mesh is as wide as the fit.
  const double equal_area = std::sqrt(2.0 * M_PI / (longitudes * std::sin(2.0 * M_PI / longitudes)));
  mesh_coords_.push_back({0.0, -1.0, 0.0, 0.0});
  for (const Ring& ring : rings)
    for (int k = 0; k < longitudes; ++k) {
      const double theta = 2.0 * M_PI * k / longitudes, rho = equal_area * ring.rho;
      mesh_coords_.push_back({ring.s, ring.c, rho * std::cos(theta), rho * std::sin(theta)});
    }
  mesh_coords_.push_back({1.0, 1.0, 0.0, 0.0});
  const int num_rings = static_cast<int>(rings.size());
  const int last = static_cast<int>(mesh_coords_.size()) - 1;
  auto ring_vertex = [&](int ring, int k) { return 1 + ring * longitudes + (k % longitudes); };
  // Local frame (e1, e2, axis) is right-handed; rings go from A (-axis) to B (+axis); theta
  // increases counter-clockwise seen from +axis.
  for (int k = 0; k < longitudes; ++k) mesh_triangles_.emplace_back(0, ring_vertex(0, k + 1), ring_vertex(0, k));
  for (int ring = 0; ring + 1 < num_rings; ++ring)
    for (int k = 0; k < longitudes; ++k) {
      const int a = ring_vertex(ring, k), b = ring_vertex(ring, k + 1);
      const int c = ring_vertex(ring + 1, k), d = ring_vertex(ring + 1, k + 1);
      mesh_triangles_.emplace_back(a, b, d);
      mesh_triangles_.emplace_back(a, d, c);
    }
  for (int k = 0; k < longitudes; ++k)
    mesh_triangles_.emplace_back(last, ring_vertex(num_rings - 1, k), ring_vertex(num_rings - 1, k + 1));

  // Fitting samples: 8 around, at cap middles and along the body, plus both poles.
  sample_coords_.push_back({0.0, -1.0, 0.0, 0.0});
  sample_coords_.push_back({1.0, 1.0, 0.0, 0.0});
  const int around = 8;
  for (int k = 0; k < around; ++k) {
    const double theta = 2.0 * M_PI * (k + 0.5) / around;
    const double x = std::cos(theta), y = std::sin(theta);
    const double h = std::sqrt(0.5);
    sample_coords_.push_back({0.0, -h, h * x, h * y});
    sample_coords_.push_back({1.0, h, h * x, h * y});
    for (double s : {0.0, 0.25, 0.5, 0.75, 1.0}) sample_coords_.push_back({s, 0.0, x, y});
  }
}

int BodyTemplate::num_dofs() const {
  int n = 6;
  for (const JointDof& d : dofs_) n += d.num_dof();
  return n;
}

std::array<Vector3d, kNumTemplateJoints> BodyTemplate::RestPositions(const BodyShape& shape) const {
  std::array<Vector3d, kNumTemplateJoints> rest;
  ti::RestPositions<double>(*this, shape.length_scale.data(), shape.girth_scale.data(), &rest);
  return rest;
}

Skeleton BodyTemplate::MakeSkeleton(const BodyShape& shape) const {
  const auto rest = RestPositions(shape);
  Skeleton skeleton;
  for (int j = 0; j < kNumTemplateJoints; ++j) {
    Joint joint;
    joint.name = joint_names_[j];
    joint.parent = parents_[j];
    joint.offset_in_parent = parents_[j] < 0 ? rest[j] : Vector3d(rest[j] - rest[parents_[j]]);
    skeleton.joints.push_back(joint);
  }
  return skeleton;
}

Pose BodyTemplate::ToPose(const TemplatePose& pose) const {
  Pose out = Pose::Rest(kNumTemplateJoints);
  out.root_translation = pose.root_translation;
  out.local_rotations[0] = Eigen::Quaterniond(ti::AngleAxisMatrix(pose.root_rotation.data()));
  for (int j = 1; j < kNumTemplateJoints; ++j)
    out.local_rotations[j] = Eigen::Quaterniond(ti::LocalRotation(dofs_[j], pose.dofs[j].data()));
  return out;
}

std::vector<Vector3d> BodyTemplate::JointPositions(const BodyShape& shape, const TemplatePose& pose) const {
  return confluent::JointPositions(MakeSkeleton(shape), ToPose(pose));
}

Mesh BodyTemplate::PosedMesh(const BodyShape& shape, const TemplatePose& pose) const {
  const auto rest = RestPositions(shape);
  const std::vector<Eigen::Isometry3d> world = WorldFromJoint(MakeSkeleton(shape), ToPose(pose));
  const int nv = static_cast<int>(mesh_coords_.size()), nf = static_cast<int>(mesh_triangles_.size());
  Mesh mesh;
  mesh.vertices.resize(nv * kNumBodySegments, 3);
  mesh.faces.resize(nf * kNumBodySegments, 3);
  mesh.face_labels.resize(nf * kNumBodySegments);
  for (int s = 0; s < kNumBodySegments; ++s) {
    const double skirt[2] = {shape.skirt_length_m, shape.skirt_flare_m};
    const ti::Section<double> section{shape.depth_scale[s], shape.taper_scale[s], shape.depth_offset[s],
                                      shape.mid_bulge[s]};
    const auto frame = ti::MakeSegmentFrame<double>(*this, s, rest, shape.length_scale.data(), shape.girth_scale.data(),
                                                    skirt, section);
    const int j = segments_[s].joint;
    for (int v = 0; v < nv; ++v) {
      const Vector3d p = frame.Point(mesh_coords_[v]);
      mesh.vertices.row(s * nv + v) = (world[j] * (p - rest[j])).transpose();
    }
    for (int f = 0; f < nf; ++f) {
      mesh.faces.row(s * nf + f) = (mesh_triangles_[f].array() + s * nv).transpose();
      mesh.face_labels[s * nf + f] = s;
    }
  }
  return mesh;
}

void BodyTemplate::ClampToLimits(TemplatePose* pose) const {
  for (int j = 0; j < kNumTemplateJoints; ++j)
    for (int k = 0; k < dofs_[j].num_dof(); ++k)
      pose->dofs[j][k] = std::clamp(pose->dofs[j][k], dofs_[j].lower[k], dofs_[j].upper[k]);
}

std::string JointMappingNote() {
  return "template joints carry the studio skeleton's names (pelvis, spine, chest, neck, head, head_end, "
         "{left,right}_{shoulder,elbow,wrist,hand_end,hip,knee,ankle,toe}); each template joint is compared with "
         "the studio joint of the same name. The joint-error metric uses the 17 articulation joints (pelvis, spine, "
         "chest, neck, head, shoulders, elbows, wrists, hips, knees, ankles), excluding the end sites "
         "(head_end, hand_end, toe), whose position is a convention of each model.";
}

}  // namespace confluent
