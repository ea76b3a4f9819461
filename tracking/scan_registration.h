#pragma once
// Registration of the body template to a scan in its own reference pose (issue 7): a 3D
// surface-to-surface fit of the template's shape and pose with Ceres, the "roughly aligned"
// reference pair that de Aguiar et al. 2006 (section 4.1) assume, plus its JSON encoding inside
// correspondences.json ("template_registration").
//
// The fit is an ICP-style alternation (Besl and McKay 1992; point-to-plane after Chen and
// Medioni 1992): template surface points are paired with their nearest scan samples of
// compatible normal (point-to-plane residuals), scan samples are paired with their nearest
// template segment (the distance to the segment's tapered elliptic capsule), and Ceres solves
// for the root, the joint angles (within their limits) and optionally the per-segment scales.
// The initial orientation comes from the principal axes of the scan, tried with both signs, so
// that scans lying on their side, upside down or in other units (decimetres, centimetres)
// are handled; the result says so in `warnings`.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "tracking/body_template.h"

namespace confluent {

// Options of RegisterTemplateToScan.
struct ScanRegistrationOptions {
  bool fit_shape = true;          // false: keep initial_shape (the run passes the tracked shape)
  BodyShape initial_shape;        // start (or fixed) shape; with fit_shape and the default (all 1)
                                  // it is first scaled uniformly to the scan's height
  // Warm start: the pose to start from (scan frame). Unset: the pose is initialised from the
  // scan's principal axes, trying both signs of the up and lateral axes.
  std::optional<TemplatePose> initial_pose;
  int num_scan_samples = 20000;   // area-uniform samples of the scan surface (nearest-point queries)
  int num_scan_residuals = 2500;  // of those, samples that get a scan -> template residual
  int rounds = 8;                 // pairing rounds of the full fit (0: initial_pose as it is, measured)
  int max_iterations = 12;        // Levenberg-Marquardt iterations per round
  double max_pair_distance_m = 0.12;    // first-round pairing distance (halves down to min_pair_distance_m)
  double min_pair_distance_m = 0.03;    // last-round pairing distance
  double max_normal_angle_deg = 60.0;   // pairs whose normals differ by more are rejected
  double loss_scale_m = 0.02;     // Huber scale of the surface residuals
  double prior_weight = 0.02;     // weight (per radian) of the prior towards the initial joint angles
  double shape_prior_weight = 2.0;      // weight of the prior towards a uniformly scaled body
  // The scan is refused (InputError) when the trimmed rms surface residual (best 90% of the
  // distances) exceeds this fraction of the body height: not human-like.
  double max_residual_fraction = 0.025;
  // Reference-pose check: warn when a segment's axis differs from the axis of the scan surface
  // paired with it by more than this, or its residual is much worse than the body's.
  double reference_pose_tolerance_deg = 20.0;
  bool allow_reorientation = true;  // false: a scan that is not upright (+z up) is refused
  int num_threads = 2;
  // Throws UsageError for out-of-range values.
  void Check() const;
};

// The result of RegisterTemplateToScan.
struct ScanRegistration {
  BodyShape shape;
  TemplatePose pose;              // template pose in the scan's frame (world, metres)
  double rms_residual_m = 0.0;    // surface-to-surface fit residual (both directions, scan units)
  double trimmed_rms_residual_m = 0.0;  // the same over the best 90% of the distances
  std::vector<double> segment_rms_m;    // per BodySegment: rms of its template -> scan distances
  double scan_height = 0.0;       // extent of the scan along its up axis, in scan units
  double metres_per_unit = 1.0;   // guessed length unit of the scan (0.1: decimetres, ...)
  Eigen::Vector3d up_in_scan = Eigen::Vector3d::UnitZ();  // the body's up (ankles to head) in the scan's frame
  std::vector<std::string> warnings;   // e.g. reference-pose check per segment, re-orientation
  // Set when the scan stands in the first tracked frame's pose but that frame's template is not
  // the reference (one of its segments is off the scan): the first tracked pose, from which the
  // deformation's first frames ease into the tracked ones (pipeline/first_pose_seam.h).
  std::optional<TemplatePose> first_tracked_pose;
};

// Fits the template (shape and pose) to a scan in its own reference pose. Throws InputError(scan_source, ...)
// when the scan is empty, when it is not human-like (reporting the residual), or when it is
// not upright and options.allow_reorientation is false; otherwise a scan lying on its side or
// upside down is handled by posing the template to match (a warning says how).
ScanRegistration RegisterTemplateToScan(const BodyTemplate& body, const Mesh& scan,
                                        const ScanRegistrationOptions& options = {},
                                        const std::string& scan_source = "scan");

// Per segment, the angle (degrees) between the segment's orientation in pose `a` and in pose
// `b` (both for `shape`): how much two reference poses differ.
std::vector<double> SegmentRotationDifferencesDeg(const BodyTemplate& body, const BodyShape& shape,
                                                  const TemplatePose& a, const TemplatePose& b);

// Adds {"template_registration": {"shape": ..., "pose": ...}} (the encoding of poses.json: shape
// as length_scale/girth_scale per segment name, pose as root_translation, root_rotation_vector
// and joint_angles per joint name) to the JSON file `correspondences_path` (an existing
// correspondences.json), rewriting it atomically. Throws InputError when the file cannot be
// read, OutputError when it cannot be written.
void WriteTemplateRegistration(const std::string& correspondences_path, const BodyTemplate& body,
                               const ScanRegistration& registration);

// Whether the correspondences.json `correspondences_path` holds a "template_registration" (given
// correspondences may not). Throws InputError naming the file when it is missing or not JSON.
bool HasTemplateRegistration(const std::string& correspondences_path);

// Reads the "template_registration" of a correspondences.json. Throws InputError naming the
// file when it is missing, is not JSON, or has no (or a malformed) "template_registration".
ScanRegistration ReadTemplateRegistration(const std::string& correspondences_path,
                                          const BodyTemplate& body = BodyTemplate());

}  // namespace confluent
