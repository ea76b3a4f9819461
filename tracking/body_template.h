#pragma once
// The tracker's 16-segment skeletal body template (after Carranza et al. 2003): a kinematic
// skeleton with 41 degrees of freedom and anatomical joint limits, sixteen closed tapered
// elliptic capsules (one per BodySegment), per-segment length and girth scales, cross-section
// depth and taper along the bone, and a skirt
// (the lower torso extended down and flared) for long skirts and dresses.
//
// Frame and units: world Z up, metres. At rest the template stands at the origin in an A-pose
// (upper arms 40 degrees from the vertical), facing +y; its left side is -x. The joints are the
// body's (core/body_model.h), as the studio actor's, so joint errors against the studio ground
// truth compare joints of the same name (see JointMappingNote()).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "core/body_model.h"
#include "core/body_segments.h"
#include "core/mesh.h"
#include "core/skeleton.h"

namespace confluent {

// The template's joints are the body's (core/body_model.h).
constexpr int kNumTemplateJoints = kNumBodyJoints;

// How a joint may rotate relative to its parent.
enum class JointType {
  kFixed,   // 0 DOF
  kBall,    // 3 DOF: a rotation vector (angle-axis, radians) in the parent's rest-aligned frame
  kHinge,   // 1 DOF: an angle about `axes[0]`
  kHinge2,  // 2 DOF: R(axes[0], q0) * R(axes[1], q1)
};

// Degrees of freedom of one joint, with box limits per DOF (radians).
struct JointDof {
  JointType type = JointType::kFixed;
  std::array<Eigen::Vector3d, 2> axes{Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()};
  std::array<double, 3> lower{0, 0, 0};
  std::array<double, 3> upper{0, 0, 0};
  // Pull of the silhouette fit towards the rest angle 0 (per radian; 0 = none): a DOF that the
  // silhouettes hardly see and that is usually at rest (a hand's sideways bend).
  std::array<double, 3> rest_weight{0, 0, 0};
  // Angle from rest beyond which the pull fades (a Cauchy loss; 0 = a quadratic pull): a real
  // bend is held only weakly, a small drift firmly.
  double rest_fade_rad = 0.0;
  int num_dof() const { return type == JointType::kBall ? 3 : type == JointType::kHinge ? 1 : type == JointType::kHinge2 ? 2 : 0; }
};

// Shape: per-segment scales of bone length and of girth (1 = the generic 1.75 m template).
struct BodyShape {
  std::array<double, kNumBodySegments> length_scale;
  std::array<double, kNumBodySegments> girth_scale;
  // Cross-sections along the bone, on top of the girth scale: the radii along e2 (front to back
  // for the torso, head and legs) relative to those along e1, the radii at end B relative to end A
  // (a taper), and, for the upper and lower torso only, the capsule moved along e2 by this
  // fraction of its e2 radius (a chest in front of the spine; a limb's axis stays on its bones).
  // Last, the radii half-way along the bone grow by mid_bulge (a parabola, 0 at the ends: a
  // chest, a calf; not the lower torso, whose profile is the skirt's). 1, 1, 0 and 0: the generic
  // template's cross-section.
  std::array<double, kNumBodySegments> depth_scale;
  std::array<double, kNumBodySegments> taper_scale;
  std::array<double, kNumBodySegments> depth_offset;
  std::array<double, kNumBodySegments> mid_bulge;
  // A garment DOF for long skirts and dresses: the lower torso's capsule extends this much
  // further down along its axis, m (0 = no skirt) ...
  double skirt_length_m = 0.0;
  // ... and its radii at that lower end grow by this much, m (a cone flaring from the waist).
  double skirt_flare_m = 0.0;
  BodyShape() {
    length_scale.fill(1.0);
    girth_scale.fill(1.0);
    depth_scale.fill(1.0);
    taper_scale.fill(1.0);
    depth_offset.fill(0.0);
    mid_bulge.fill(0.0);
  }
  // A uniformly scaled template of `height_m` (lengths and girths scaled alike).
  static BodyShape Uniform(double height_m);
};

// The largest skirt (BodyShape::skirt_length_m, skirt_flare_m) for a body whose lengths and girths
// are scaled by about these factors: down to about the ground, flared like a wide dress. The
// silhouette fit's bounds and the skirt search's grid (tracking/skirt_search.h).
inline std::array<double, 2> MaxSkirt(double length_scale, double girth_scale) {
  return {0.9 * length_scale, 0.3 * girth_scale};
}

// A pose of the template: root translation and rotation plus all joint DOFs.
struct TemplatePose {
  Eigen::Vector3d root_translation = Eigen::Vector3d::Zero();  // added to the rest pelvis position, m
  Eigen::Vector3d root_rotation = Eigen::Vector3d::Zero();     // world rotation vector (angle-axis), rad
  std::array<std::array<double, 3>, kNumTemplateJoints> dofs{};  // per joint, num_dof() values used
};

// One segment's tapered elliptic capsule in the rest pose of the generic template. The axis
// runs from A = rest[joint_a] + offset_a to B = rest[joint_b] + offset_b (offsets scaled by the
// segment's length scale); radii along e1 (from `e1_hint`) and e2 = axis x e1 go linearly from
// radii_a to radii_b; the ends are half-ellipsoids with axial radius cap_a / cap_b. Radii and
// caps are scaled by the girth scale.
struct SegmentShape {
  int joint = 0;  // the joint whose transform moves the segment rigidly
  int joint_a = 0, joint_b = 0;
  Eigen::Vector3d offset_a = Eigen::Vector3d::Zero(), offset_b = Eigen::Vector3d::Zero();
  Eigen::Vector2d radii_a = Eigen::Vector2d::Zero(), radii_b = Eigen::Vector2d::Zero();
  double cap_a = 0.0, cap_b = 0.0;
  Eigen::Vector3d e1_hint = Eigen::Vector3d::UnitX();
};

// A point of a segment surface in capsule coordinates: axial fraction s in [0,1], cap
// coordinate c in [-1,1] (negative: cap A, multiplied by cap_a; positive: cap B), and unit
// cross-section coordinates (x, y) multiplied by the radii at s.
struct SurfaceCoord {
  double s = 0, c = 0, x = 0, y = 0;
};

// The template: skeleton, DOFs with limits, segment shapes and the surface meshing.
class BodyTemplate {
 public:
  // The generic template (1.75 m), meshed with `longitudes` steps around each segment.
  explicit BodyTemplate(int longitudes = 12);

  // Joint names (BodyJointNames), parents and the generic rest positions (m).
  const std::vector<std::string>& joint_names() const { return joint_names_; }
  const std::array<int, kNumTemplateJoints>& parents() const { return parents_; }
  const std::array<Eigen::Vector3d, kNumTemplateJoints>& generic_rest() const { return generic_rest_; }
  const std::array<JointDof, kNumTemplateJoints>& dofs() const { return dofs_; }
  const std::array<SegmentShape, kNumBodySegments>& segments() const { return segments_; }
  // For each joint, the segment whose length scale scales its offset from the parent (-1 root).
  const std::array<int, kNumTemplateJoints>& offset_segment() const { return offset_segment_; }
  // Total number of pose DOFs (6 root + joints).
  int num_dofs() const;

  // Rest joint positions for `shape` (m).
  std::array<Eigen::Vector3d, kNumTemplateJoints> RestPositions(const BodyShape& shape) const;
  // The skeleton (core/skeleton.h) for `shape`, joint 0 = pelvis.
  Skeleton MakeSkeleton(const BodyShape& shape) const;
  // The pose as core Pose (local rotations as quaternions) for MakeSkeleton(shape).
  Pose ToPose(const TemplatePose& pose) const;
  // World joint positions of `pose` (m).
  std::vector<Eigen::Vector3d> JointPositions(const BodyShape& shape, const TemplatePose& pose) const;

  // Surface coordinates of the mesh vertices of each segment (the same for every segment) and
  // the triangles over them (CCW outward), and a coarser set used as fitting samples.
  const std::vector<SurfaceCoord>& mesh_coords() const { return mesh_coords_; }
  const std::vector<Eigen::Vector3i>& mesh_triangles() const { return mesh_triangles_; }
  const std::vector<SurfaceCoord>& sample_coords() const { return sample_coords_; }

  // The posed template mesh: 16 closed components, face_labels = BodySegment.
  Mesh PosedMesh(const BodyShape& shape, const TemplatePose& pose) const;

  // Clamps every DOF of `pose` into its limits.
  void ClampToLimits(TemplatePose* pose) const;

 private:
  std::vector<std::string> joint_names_;
  std::array<int, kNumTemplateJoints> parents_{};
  std::array<Eigen::Vector3d, kNumTemplateJoints> generic_rest_;
  std::array<JointDof, kNumTemplateJoints> dofs_;
  std::array<SegmentShape, kNumBodySegments> segments_;
  std::array<int, kNumTemplateJoints> offset_segment_{};
  std::vector<SurfaceCoord> mesh_coords_;
  std::vector<Eigen::Vector3i> mesh_triangles_;
  std::vector<SurfaceCoord> sample_coords_;
};

// How the template joints map to the studio skeleton's joints for joint-error metrics: the
// same names; a text for reports.
std::string JointMappingNote();

}  // namespace confluent
