#pragma once
// INTERNAL (tracking/*.cc only): the template's geometry and kinematics, templated on the
// scalar type so that the same code serves the exporter (double) and the Ceres cost functors
// (ceres::Jet).

#include <Eigen/Core>
#include <array>
#include <cmath>

#include "tracking/body_template.h"

namespace confluent::tracking_internal {

template <typename T> using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T> using Mat3 = Eigen::Matrix<T, 3, 3>;

// Shape groups shared by left and right: head, neck, upper torso, lower torso, upper arm,
// forearm, hand, thigh, shank, foot.
constexpr int kNumShapeGroups = 10;

constexpr double kDeg = M_PI / 180.0;  // one degree in radians
constexpr int kSegmentGroup[kNumBodySegments] = {0, 1, 2, 3, 4, 5, 6, 4, 5, 6, 7, 8, 9, 7, 8, 9};

using std::cos;
using std::sin;
using std::sqrt;

// Rodrigues' formula for a rotation vector (radians), first order near zero.
template <typename T>
Mat3<T> AngleAxisMatrix(const T* aa) {
  const T theta2 = aa[0] * aa[0] + aa[1] * aa[1] + aa[2] * aa[2];
  Mat3<T> R;
  if (theta2 > T(1e-14)) {
    const T theta = sqrt(theta2);
    const T wx = aa[0] / theta, wy = aa[1] / theta, wz = aa[2] / theta;
    const T c = cos(theta), s = sin(theta), one_c = T(1.0) - c;
    R(0, 0) = c + wx * wx * one_c;      R(0, 1) = wx * wy * one_c - wz * s; R(0, 2) = wy * s + wx * wz * one_c;
    R(1, 0) = wz * s + wx * wy * one_c; R(1, 1) = c + wy * wy * one_c;      R(1, 2) = -wx * s + wy * wz * one_c;
    R(2, 0) = -wy * s + wx * wz * one_c; R(2, 1) = wx * s + wy * wz * one_c; R(2, 2) = c + wz * wz * one_c;
  } else {
    R(0, 0) = T(1.0);  R(0, 1) = -aa[2]; R(0, 2) = aa[1];
    R(1, 0) = aa[2];   R(1, 1) = T(1.0); R(1, 2) = -aa[0];
    R(2, 0) = -aa[1];  R(2, 1) = aa[0];  R(2, 2) = T(1.0);
  }
  return R;
}

// Rotation about a unit axis by `angle`.
template <typename T>
Mat3<T> AxisRotation(const Eigen::Vector3d& axis, const T& angle) {
  const T aa[3] = {T(axis.x()) * angle, T(axis.y()) * angle, T(axis.z()) * angle};
  return AngleAxisMatrix(aa);
}

// A joint's rotation relative to its parent from its DOF values.
template <typename T>
Mat3<T> LocalRotation(const JointDof& dof, const T* q) {
  switch (dof.type) {
    case JointType::kBall: return AngleAxisMatrix(q);
    case JointType::kHinge: return AxisRotation(dof.axes[0], q[0]);
    case JointType::kHinge2: return AxisRotation(dof.axes[0], q[0]) * AxisRotation(dof.axes[1], q[1]);
    default: return Mat3<T>::Identity();
  }
}

// Rest joint positions from per-segment length and girth scales (each kNumBodySegments long).
template <typename T>
void RestPositions(const BodyTemplate& body, const T* length, const T* girth, std::array<Vec3<T>, kNumTemplateJoints>* rest) {
  const auto& generic = body.generic_rest();
  (*rest)[0] = generic[0].cast<T>();
  for (int j = 1; j < kNumTemplateJoints; ++j) {
    const int p = body.parents()[j];
    const Eigen::Vector3d offset = generic[j] - generic[p];
    const int seg = body.offset_segment()[j];
    Vec3<T> scaled = offset.cast<T>() * length[seg];
    // Shoulders and hips sit laterally: their x offset follows the torso's girth.
    if (j == kJointLeftShoulder || j == kJointRightShoulder || j == kJointLeftHip || j == kJointRightHip)
      scaled.x() = T(offset.x()) * girth[seg];
    (*rest)[j] = (*rest)[p] + scaled;
  }
}

// A segment's capsule at rest, for given rest joints and scales.
template <typename T>
struct SegmentFrame {
  Vec3<T> a, axis, e1, e2;
  T length;
  T rax, ray, rbx, rby, cap_a, cap_b;
  T bulge = T(0.0);  // the radii half-way along grow by this fraction (BodyShape::mid_bulge)

  // The radii at axial fraction `f` in [0, 1]: linear from end A to end B, grown by the bulge
  // (a parabola that is 0 at both ends).
  void Radii(const T& f, T* rx, T* ry) const {
    const T grow = T(1.0) + bulge * T(4.0) * f * (T(1.0) - f);
    *rx = (rax + (rbx - rax) * f) * grow;
    *ry = (ray + (rby - ray) * f) * grow;
  }

  // The rest-pose point of surface coordinate `sc`.
  Vec3<T> Point(const SurfaceCoord& sc) const {
    T rx, ry;
    Radii(T(sc.s), &rx, &ry);
    const T cap = sc.c < 0 ? cap_a : cap_b;
    return a + axis * (length * T(sc.s) + cap * T(sc.c)) + e1 * (rx * T(sc.x)) + e2 * (ry * T(sc.y));
  }

  // The same capsule in another scalar type.
  template <typename U>
  SegmentFrame<U> Cast() const {
    SegmentFrame<U> f;
    f.a = a.template cast<U>();
    f.axis = axis.template cast<U>();
    f.e1 = e1.template cast<U>();
    f.e2 = e2.template cast<U>();
    f.length = U(length);
    f.rax = U(rax);
    f.ray = U(ray);
    f.rbx = U(rbx);
    f.rby = U(rby);
    f.cap_a = U(cap_a);
    f.cap_b = U(cap_b);
    f.bulge = U(bulge);
    return f;
  }
};

// A segment's cross-section on top of its girth: BodyShape::depth_scale, taper_scale,
// depth_offset (the torso's only) and mid_bulge (not the lower torso's).
template <typename T>
struct Section {
  T depth = T(1.0), taper = T(1.0), offset = T(0.0), bulge = T(0.0);
};

// `skirt` (may be null): {skirt_length_m, skirt_flare_m} of BodyShape, applied to the lower torso.
template <typename T>
SegmentFrame<T> MakeSegmentFrame(const BodyTemplate& body, int segment, const std::array<Vec3<T>, kNumTemplateJoints>& rest,
                                 const T* length, const T* girth, const T* skirt = nullptr,
                                 const Section<T>& section = Section<T>()) {
  const SegmentShape& shape = body.segments()[segment];
  SegmentFrame<T> f;
  f.a = rest[shape.joint_a] + shape.offset_a.cast<T>() * length[segment];
  const Vec3<T> b = rest[shape.joint_b] + shape.offset_b.cast<T>() * length[segment];
  Vec3<T> d = b - f.a;
  f.length = sqrt(d.squaredNorm() + T(1e-12));
  f.axis = d / f.length;
  const bool skirted = skirt != nullptr && segment == int(BodySegment::kLowerTorso);
  if (skirted) {
    f.a = f.a - f.axis * skirt[0];
    f.length = f.length + skirt[0];
  }
  const Vec3<T> hint = shape.e1_hint.cast<T>();
  Vec3<T> e1 = hint - f.axis * hint.dot(f.axis);
  f.e1 = e1 / sqrt(e1.squaredNorm() + T(1e-12));
  f.e2 = f.axis.cross(f.e1);
  const T g = girth[segment];
  f.rax = T(shape.radii_a.x()) * g;
  f.ray = T(shape.radii_a.y()) * g * section.depth;
  f.rbx = T(shape.radii_b.x()) * g * section.taper;
  f.rby = T(shape.radii_b.y()) * g * section.depth * section.taper;
  f.cap_a = T(shape.cap_a) * g;
  f.cap_b = T(shape.cap_b) * g * section.taper;
  // The lower torso's profile below the waist is the skirt's (a bulge there would stand in for a
  // skirt and keep the skirt from being found).
  if (segment != int(BodySegment::kLowerTorso)) f.bulge = section.bulge;
  // The spine lies behind the torso's middle; a limb's axis runs through its joints.
  if (segment == int(BodySegment::kUpperTorso) || segment == int(BodySegment::kLowerTorso))
    f.a = f.a + f.e2 * (section.offset * T(0.5) * (f.ray + f.rby));
  if (skirted) {
    f.rax = f.rax + skirt[1];
    f.ray = f.ray + skirt[1];
  }
  return f;
}

// World transform of joint `joint`: rotation R and position P. `root_aa` is a world rotation
// vector applied on top of `root_reference` (world_from_pelvis = R(root_aa) * root_reference);
// `joint_params[k]` points at joint k's DOF values (may be null for fixed joints).
template <typename T>
void JointWorldTransform(const BodyTemplate& body, int joint, const std::array<Vec3<T>, kNumTemplateJoints>& rest,
                         const T* root_translation, const T* root_aa, const Eigen::Matrix3d& root_reference,
                         const T* const* joint_params, Mat3<T>* R, Vec3<T>* P) {
  int chain[kNumTemplateJoints];
  int n = 0;
  for (int j = joint; j > 0; j = body.parents()[j]) chain[n++] = j;
  *R = AngleAxisMatrix(root_aa) * root_reference.cast<T>();
  *P = rest[0] + Vec3<T>(root_translation[0], root_translation[1], root_translation[2]);
  for (int i = n - 1; i >= 0; --i) {
    const int j = chain[i];
    const int p = body.parents()[j];
    *P = *P + *R * (rest[j] - rest[p]);
    if (body.dofs()[j].type != JointType::kFixed) *R = *R * LocalRotation(body.dofs()[j], joint_params[j]);
  }
}

}  // namespace confluent::tracking_internal
