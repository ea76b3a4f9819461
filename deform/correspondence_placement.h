#pragma once
// Automatic placement of template <-> scan triangle correspondences (issue 7), following the
// marking rules of de Aguiar et al. 2006, section 4.2 and Figure 4: per body segment, rings of
// template triangles around the limb, denser rings at the complex regions (shoulders, hips and
// lap), all kept a configurable distance away from the joints; each paired with the scan
// triangle hit along the template normal (or the nearest one), with consistency checks on the
// normals and on the side of the body. Works on meshes only: the template comes in as a posed
// mesh with segment labels (deform does not depend on tracking).

#include <Eigen/Core>
#include <vector>

#include "core/mesh.h"
#include "deform/correspondences.h"

namespace confluent {

// Options of PlaceCorrespondences. Lengths are in metres; `metres_per_unit` converts them to
// the meshes' units.
struct CorrespondencePlacementOptions {
  // Markers keep at least this distance from the joints (along the limb for the joints at a
  // segment's ends): nearer markers give a sharper bend of the skin at the joint (Figure 4).
  // On short segments it is at most 15% of the segment's extent, so that they keep markers.
  double joint_clearance_m = 0.05;
  // The positions of the joints where two segments meet (mesh units, the template mesh's frame;
  // SetBodyJoints below). Empty: estimated at both ends of each segment's axis, one local radius
  // inside.
  std::vector<Eigen::Vector3d> joint_positions;
  // The clearance of each joint of joint_positions, times joint_clearance_m (missing: 1).
  std::vector<double> joint_clearance_scales;
  double metres_per_unit = 1.0;       // size of one mesh unit (0.1 for decimetres)
  int limb_ring_markers = 6;          // markers per ring on the limbs, neck and head
  int dense_ring_markers = 10;        // markers per ring at the shoulders and at the hips/lap
  double max_pair_distance_m = 0.06;  // scan triangle along the template normal, or nearest, within this
  double max_normal_angle_deg = 60.0; // template and scan normals of a pair agree within this
  double side_margin_m = 0.02;        // left/right check only beyond this distance from the midplane
  double manual_spacing_m = 0.03;     // automatic markers this close to a manual one are dropped
  // Throws UsageError for out-of-range values.
  void Check() const;
};

// Sets `options`' joints from the body's 22 joint positions (core/body_model.h order): only those
// where two segments meet (JointJoinsSegments; a joint inside a segment, the pelvis or the chest,
// would clear a band of it of markers for no bend), the spine's clearance doubled (the skin of the
// lower back and the belly bends over a longer stretch than at a limb's joint).
void SetBodyJoints(const std::vector<Eigen::Vector3d>& body_joints, CorrespondencePlacementOptions* options);

// template_mesh: the posed template in the registered reference pose, face_labels = segment ids
// (core/body_segments.h names). Returns pairs with segment labels; `manual` pairs (may be null) are
// kept (first, labelled from the template when unlabelled) and the automatic ones complete them,
// never reusing a triangle. Both meshes must be roughly aligned (same frame and units). Throws
// InputError("template", ...) when the template has no face labels, InputError("manual
// correspondences", ...) when a manual index is out of range.
Correspondences PlaceCorrespondences(const Mesh& template_mesh, const Mesh& scan,
                                     const CorrespondencePlacementOptions& options = {},
                                     const Correspondences* manual = nullptr);

}  // namespace confluent
