#include "tracking/segment_costs.h"

#include <ceres/jet.h>

#include <stdexcept>
#include <string>

#include "tracking/fit_params.h"

namespace confluent::tracking_internal {

using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

// The capsule's values from its end and axes (in some frame) and its rest frame's scalars.
template <typename T>
void PackCapsule(const Vec3<T>& a, const Vec3<T>& axis, const Vec3<T>& e1, const Vec3<T>& e2,
                 const SegmentFrame<T>& frame, T* values) {
  for (int k = 0; k < 3; ++k) {
    values[k] = a[k];
    values[3 + k] = axis[k];
    values[6 + k] = e1[k];
    values[9 + k] = e2[k];
  }
  const T scalars[8] = {frame.length, frame.cap_a, frame.cap_b, frame.rax, frame.rbx, frame.ray, frame.rby, frame.bulge};
  for (int k = 0; k < 8; ++k) values[12 + k] = scalars[k];
}

// A ray seen from a capsule: its origin relative to end A and its direction, each along e1,
// e2 and the axis.
struct RayInCapsule {
  double o[3], d[3];
  RayInCapsule(const CapsuleValues& capsule, const Vector3d& origin, const Vector3d& direction) {
    const Vector3d offset = origin - capsule.segment<3>(0);
    const Vector3d axes[3] = {capsule.segment<3>(6), capsule.segment<3>(9), capsule.segment<3>(3)};
    for (int k = 0; k < 3; ++k) {
      o[k] = offset.dot(axes[k]);
      d[k] = direction.dot(axes[k]);
    }
  }
};

// The normalised distance of the ray to the capsule (1 on its surface), from the ray's local
// coordinates (o, d: along e1, e2, axis) and the capsule's scalars (length, cap_a, cap_b, rax,
// rbx, ray, rby, bulge); in `mean_radius` the capsule's mean radius where the ray passes.
template <typename T>
T RayCapsuleDistance(const T* o, const T* d, const T* scalars, T* mean_radius) {
  SegmentFrame<T> capsule;  // its scalars only: the ray is already in its frame
  T* fields[8] = {&capsule.length, &capsule.cap_a, &capsule.cap_b, &capsule.rax,
                  &capsule.rbx,    &capsule.ray,   &capsule.rby,   &capsule.bulge};
  for (int k = 0; k < 8; ++k) *fields[k] = scalars[k];
  const T& length = capsule.length;
  const T &ox = o[0], &oy = o[1], &oz = o[2], &dx = d[0], &dy = d[1], &dz = d[2];
  const T d_o = dx * ox + dy * oy + dz * oz;
  const T denom = T(1.0) - dz * dz;
  T s = denom > T(1e-6) ? (oz - dz * d_o) / denom : oz;  // closest approach along the axis
  bool clamped = false;
  if (s < T(0.0)) { s = T(0.0); clamped = true; }
  if (s > length) { s = length; clamped = true; }
  T rx, ry;
  capsule.Radii(s / length, &rx, &ry);
  const T qz0 = oz - s;
  const T inv_cap = clamped ? T(1.0) / (qz0 < T(0.0) ? capsule.cap_a : capsule.cap_b) : T(0.0);
  const T av[3] = {ox / rx, oy / ry, qz0 * inv_cap}, bv[3] = {dx / rx, dy / ry, dz * inv_cap};
  const T tau = -(av[0] * bv[0] + av[1] * bv[1] + av[2] * bv[2]) / (bv[0] * bv[0] + bv[1] * bv[1] + bv[2] * bv[2] + T(1e-12));
  const T q[3] = {av[0] + tau * bv[0], av[1] + tau * bv[1], av[2] + tau * bv[2]};
  *mean_radius = T(0.5) * (rx + ry);
  return sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + T(1e-12));
}

// d(distorted normalised point) / d(normalised point) for OpenCV's k1 k2 p1 p2 k3 model.
Eigen::Matrix2d DistortionJacobian(const Camera& camera, double x, double y) {
  const double k1 = camera.dist(0), k2 = camera.dist(1), p1 = camera.dist(2), p2 = camera.dist(3), k3 = camera.dist(4);
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double dradial = k1 + r2 * (2.0 * k2 + 3.0 * k3 * r2);  // d radial / d r2
  Eigen::Matrix2d J;
  J(0, 0) = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
  J(0, 1) = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
  J(1, 0) = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
  J(1, 1) = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
  return J;
}

}  // namespace

CapsuleValues CapsuleAt(const SegmentFrame<double>& frame, const Vector3d& a, const Vector3d& axis, const Vector3d& e1,
                        const Vector3d& e2) {
  CapsuleValues values;
  PackCapsule<double>(a, axis, e1, e2, frame, values.data());
  return values;
}

double RayCapsuleDistance(const CapsuleValues& capsule, const Vector3d& origin, const Vector3d& direction) {
  const RayInCapsule ray(capsule, origin, direction);
  double mean_radius;
  return RayCapsuleDistance<double>(ray.o, ray.d, capsule.data() + 12, &mean_radius);
}

SegmentCapsuleCost::SegmentCapsuleCost(const BodyTemplate& body, int segment, std::vector<int> chain_joints,
                                       const Matrix3d& root_reference, SegmentShapeBlocks shape,
                                       const Matrix3d& rotation, const Vector3d& translation, int num_residuals)
    : body_(body),
      segment_(segment),
      joint_(body.segments()[segment].joint),
      chain_joints_(std::move(chain_joints)),
      root_reference_(root_reference),
      shape_(std::move(shape)),
      rotation_(rotation),
      translation_(translation) {
  if ((shape_.skirt || shape_.section) && !shape_.shape)
    throw std::invalid_argument("SegmentCapsuleCost: a skirt or section block without the shape block");
  if (shape_.shape && !shape_.section && static_cast<int>(shape_.section_values.size()) != kSectionBlockSize)
    throw std::invalid_argument("SegmentCapsuleCost: the fixed cross-sections need " +
                                std::to_string(kSectionBlockSize) + " values");
  AddParameterBlock(3);
  AddParameterBlock(3);
  for (int j : chain_joints_) {
    AddParameterBlock(body.dofs()[j].num_dof());
    num_parameters_ += body.dofs()[j].num_dof();
  }
  if (num_parameters_ > kMaxPoseParameters)
    throw std::invalid_argument("SegmentCapsuleCost: " + std::to_string(num_parameters_) +
                                " pose parameters, at most " + std::to_string(kMaxPoseParameters));
  for (auto [present, size] : {std::pair{shape_.shape, kShapeBlockSize}, std::pair{shape_.skirt, 2},
                               std::pair{shape_.section, kSectionBlockSize}})
    if (present) {
      AddParameterBlock(size);
      num_parameters_ += size;
    }
  if (num_parameters_ > kMaxParameters)
    throw std::invalid_argument("SegmentCapsuleCost: " + std::to_string(num_parameters_) + " parameters, at most " +
                                std::to_string(kMaxParameters));
  SetNumResiduals(num_residuals);
}

template <typename T>
void SegmentCapsuleCost::Capsule(T const* const* p, T* values) const {
  const T* jp[kNumTemplateJoints] = {};
  for (std::size_t i = 0; i < chain_joints_.size(); ++i) jp[chain_joints_[i]] = p[2 + i];
  std::array<Vec3<T>, kNumTemplateJoints> rest;
  SegmentFrame<T> frame;
  if (!shape_.shape) {
    for (int j = 0; j < kNumTemplateJoints; ++j) rest[j] = shape_.rest[j].cast<T>();
    frame = shape_.frame.Cast<T>();
  } else {
    const std::size_t next = 2 + chain_joints_.size();
    const T* shape = p[next];
    T length[kNumBodySegments], girth[kNumBodySegments];
    ShapeArrays(shape, length, girth);
    RestPositions(body_, length, girth, &rest);
    const T fixed_skirt[2] = {T(shape_.skirt_values[0]), T(shape_.skirt_values[1])};
    const T* skirt = shape_.skirt ? p[next + 1] : fixed_skirt;
    Section<T> section;
    if (shape_.section) {
      section = SegmentSection(p[next + 1 + (shape_.skirt ? 1 : 0)], segment_);
    } else {
      const Section<double> fixed = SegmentSection(shape_.section_values.data(), segment_);
      section = {T(fixed.depth), T(fixed.taper), T(fixed.offset), T(fixed.bulge)};
    }
    frame = MakeSegmentFrame(body_, segment_, rest, length, girth, skirt, section);
  }
  Mat3<T> R;
  Vec3<T> P;
  JointWorldTransform(body_, joint_, rest, p[0], p[1], root_reference_, jp, &R, &P);
  const Mat3<T> M = rotation_.cast<T>() * R;
  const Vec3<T> a = M * (frame.a - rest[joint_]) + rotation_.cast<T>() * P + translation_.cast<T>();
  PackCapsule<T>(a, M * frame.axis, M * frame.e1, M * frame.e2, frame, values);
}

template <int N>
void SegmentCapsuleCost::DifferentiateCapsule(double const* const* parameters, CapsuleValues* values,
                                              CapsuleJacobian* jacobian) const {
  using Jet = ceres::Jet<double, N>;
  std::array<Jet, N> all;  // every parameter, slot by slot
  std::vector<const Jet*> pointers;
  int slot = 0;
  for (std::size_t b = 0; b < parameter_block_sizes().size(); ++b) {
    pointers.push_back(&all[slot]);
    for (int k = 0; k < parameter_block_sizes()[b]; ++k, ++slot) all[slot] = Jet(parameters[b][k], slot);
  }
  Jet capsule[kNumCapsuleValues];
  Capsule<Jet>(pointers.data(), capsule);
  for (int i = 0; i < kNumCapsuleValues; ++i) {
    (*values)(i) = capsule[i].a;
    jacobian->row(i) = capsule[i].v.head(num_parameters_).transpose();
  }
}

bool SegmentCapsuleCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const int num_blocks = static_cast<int>(parameter_block_sizes().size());
  bool want_jacobian = false;
  for (int b = 0; b < num_blocks && jacobians; ++b) want_jacobian |= jacobians[b] != nullptr;

  CapsuleValues capsule;
  CapsuleJacobian dcapsule(kNumCapsuleValues, num_parameters_);
  if (!want_jacobian)
    Capsule<double>(parameters, capsule.data());
  else if (num_parameters_ <= 12)
    DifferentiateCapsule<12>(parameters, &capsule, &dcapsule);
  else if (num_parameters_ <= 18)
    DifferentiateCapsule<18>(parameters, &capsule, &dcapsule);
  else if (num_parameters_ <= kMaxPoseParameters)
    DifferentiateCapsule<kMaxPoseParameters>(parameters, &capsule, &dcapsule);
  else
    DifferentiateCapsule<kMaxParameters>(parameters, &capsule, &dcapsule);
  // Without the shape the capsule's scalars are constants: only its end and axes move.
  const int moving_values = shape_.shape ? kNumCapsuleValues : 12;

  Eigen::RowVectorXd row(num_parameters_);
  CapsuleGradient gradient;
  for (int i = 0; i < num_residuals(); ++i) {
    const bool moving = Residual(i, capsule, &residuals[i], want_jacobian ? &gradient : nullptr);
    if (!want_jacobian) continue;
    if (moving) row.noalias() = gradient.head(moving_values) * dcapsule.topRows(moving_values);
    int offset = 0;
    for (int b = 0; b < num_blocks; ++b) {
      const int size = parameter_block_sizes()[b];
      if (jacobians[b]) {
        double* out = jacobians[b] + i * size;
        for (int k = 0; k < size; ++k) out[k] = moving ? row(offset + k) : 0.0;
      }
      offset += size;
    }
  }
  return true;
}

SegmentSamplesCost::SegmentSamplesCost(const BodyTemplate& body, int segment, std::vector<int> chain_joints,
                                       const Matrix3d& root_reference, SegmentShapeBlocks shape,
                                       std::vector<SurfaceCoord> samples, const Camera& camera, double scale,
                                       const SignedDistanceInterpolator& distance)
    : SegmentCapsuleCost(body, segment, std::move(chain_joints), root_reference, std::move(shape), camera.rotation,
                         camera.translation, static_cast<int>(samples.size())),
      samples_(std::move(samples)),
      camera_(camera),
      scale_(scale),
      distance_(distance) {}

bool SegmentSamplesCost::Residual(int i, const CapsuleValues& capsule, double* residual,
                                  CapsuleGradient* gradient) const {
  const SurfaceCoord& sc = samples_[i];
  const Vector3d a = capsule.segment<3>(0), axis = capsule.segment<3>(3), e1 = capsule.segment<3>(6),
                 e2 = capsule.segment<3>(9);
  const double length = capsule(12), cap_a = capsule(13), cap_b = capsule(14), rax = capsule(15), rbx = capsule(16),
               ray = capsule(17), rby = capsule(18), bulge = capsule(19);
  const double grow = 1.0 + bulge * 4.0 * sc.s * (1.0 - sc.s);
  const double linear_x = rax + (rbx - rax) * sc.s, linear_y = ray + (rby - ray) * sc.s;
  const double rx = linear_x * grow, ry = linear_y * grow;
  const double along = length * sc.s + (sc.c < 0 ? cap_a : cap_b) * sc.c;
  const Vector3d Xc = a + axis * along + e1 * (rx * sc.x) + e2 * (ry * sc.y);  // in the camera
  *residual = 0.0;
  if (Xc.z() < 1e-3) return false;
  const double x = Xc.x() / Xc.z(), y = Xc.y() / Xc.z();
  const bool distorted = camera_.has_distortion();
  const Eigen::Vector2d xd = distorted ? camera_.Distort(Eigen::Vector2d(x, y)) : Eigen::Vector2d(x, y);
  const Matrix3d& K = camera_.K;
  const double inv_scale = 1.0 / scale_;
  const double us = (K(0, 0) * xd.x() + K(0, 1) * xd.y() + K(0, 2) + 0.5) * inv_scale - 0.5;
  const double vs = (K(1, 1) * xd.y() + K(1, 2) + 0.5) * inv_scale - 0.5;
  double sd, dsd_dv, dsd_du;
  distance_.Evaluate(vs, us, &sd, &dsd_dv, &dsd_du);
  if (sd <= 0.0) return false;  // inside is free; an inward margin would fit the template thin
  *residual = sd;
  if (!gradient) return true;
  // d residual / d Xc, through the pixel and the distortion.
  const Eigen::RowVector2d g_xd(dsd_du * K(0, 0) * inv_scale, (dsd_du * K(0, 1) + dsd_dv * K(1, 1)) * inv_scale);
  const Eigen::RowVector2d gn = distorted ? Eigen::RowVector2d(g_xd * DistortionJacobian(camera_, x, y)) : g_xd;
  const Vector3d g(gn.x() / Xc.z(), gn.y() / Xc.z(), -(gn.x() * x + gn.y() * y) / Xc.z());
  // Then by the capsule's values (PackCapsule's order).
  const double g_axis = g.dot(axis), g_e1 = g.dot(e1) * sc.x, g_e2 = g.dot(e2) * sc.y;
  gradient->segment<3>(0) = g.transpose();
  gradient->segment<3>(3) = along * g.transpose();
  gradient->segment<3>(6) = (rx * sc.x) * g.transpose();
  gradient->segment<3>(9) = (ry * sc.y) * g.transpose();
  (*gradient)(12) = g_axis * sc.s;
  (*gradient)(13) = sc.c < 0 ? g_axis * sc.c : 0.0;
  (*gradient)(14) = sc.c < 0 ? 0.0 : g_axis * sc.c;
  (*gradient)(15) = g_e1 * (1.0 - sc.s) * grow;
  (*gradient)(16) = g_e1 * sc.s * grow;
  (*gradient)(17) = g_e2 * (1.0 - sc.s) * grow;
  (*gradient)(18) = g_e2 * sc.s * grow;
  (*gradient)(19) = (g_e1 * linear_x + g_e2 * linear_y) * 4.0 * sc.s * (1.0 - sc.s);
  return true;
}

SegmentRaysCost::SegmentRaysCost(const BodyTemplate& body, int segment, std::vector<int> chain_joints,
                                 const Matrix3d& root_reference, SegmentShapeBlocks shape,
                                 std::vector<Vector3d> origins, std::vector<Vector3d> directions, double weight)
    : SegmentCapsuleCost(body, segment, std::move(chain_joints), root_reference, std::move(shape),
                         Matrix3d::Identity(), Vector3d::Zero(), static_cast<int>(origins.size())),
      origins_(std::move(origins)),
      directions_(std::move(directions)),
      weight_(weight) {
  if (origins_.size() != directions_.size())
    throw std::invalid_argument("SegmentRaysCost: " + std::to_string(origins_.size()) + " origins, " +
                                std::to_string(directions_.size()) + " directions");
}

bool SegmentRaysCost::Residual(int i, const CapsuleValues& capsule, double* residual, CapsuleGradient* gradient) const {
  const RayInCapsule ray(capsule, origins_[i], directions_[i]);
  if (!gradient) {
    double mean_radius;
    *residual = (RayCapsuleDistance<double>(ray.o, ray.d, capsule.data() + 12, &mean_radius) - 1.0) * mean_radius * weight_;
    return true;
  }
  // Differentiated by the ray's local coordinates and the capsule's scalars (14 values) ...
  using Jet = ceres::Jet<double, 14>;
  Jet o[3], d[3], scalars[8];
  for (int k = 0; k < 3; ++k) {
    o[k] = Jet(ray.o[k], k);
    d[k] = Jet(ray.d[k], 3 + k);
  }
  for (int k = 0; k < 8; ++k) scalars[k] = Jet(capsule(12 + k), 6 + k);
  Jet mean_radius;
  const Jet r = (RayCapsuleDistance<Jet>(o, d, scalars, &mean_radius) - Jet(1.0)) * mean_radius * Jet(weight_);
  *residual = r.a;
  // ... then by the capsule's end and axes: o_k = (origin - A) . axis_k, d_k = direction . axis_k.
  const Vector3d offset = origins_[i] - capsule.segment<3>(0);
  const Vector3d& direction = directions_[i];
  const double* g = r.v.data();  // by o (e1, e2, axis), d (e1, e2, axis), scalars
  gradient->segment<3>(0) = -(g[0] * capsule.segment<3>(6) + g[1] * capsule.segment<3>(9) + g[2] * capsule.segment<3>(3)).transpose();
  gradient->segment<3>(3) = (g[2] * offset + g[5] * direction).transpose();
  gradient->segment<3>(6) = (g[0] * offset + g[3] * direction).transpose();
  gradient->segment<3>(9) = (g[1] * offset + g[4] * direction).transpose();
  for (int k = 0; k < 8; ++k) (*gradient)(12 + k) = g[6 + k];
  return true;
}

}  // namespace confluent::tracking_internal
