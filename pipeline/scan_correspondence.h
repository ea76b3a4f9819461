#pragma once
// The template registered to the actor's scan, and the template <-> scan triangle pairs that
// drive Confluent Motion: placed automatically (with optional manual pairs first) or read from
// a given file. The one implementation behind `run`, `correspond` and `animate`.

#include <functional>
#include <optional>
#include <string>

#include "core/mesh.h"
#include "deform/correspondence_placement.h"
#include "deform/correspondences.h"
#include "tracking/body_template.h"
#include "tracking/scan_registration.h"

namespace confluent {

struct ScanCorrespondenceOptions {
  // The body's shape when it is known (the tracked one): only the pose is registered, and the
  // reference template keeps exactly this shape. Absent: the shape is fitted to the scan.
  std::optional<BodyShape> known_shape;
  std::optional<TemplatePose> initial_pose;  // where the registration starts (a tracked pose)
  // Without initial_pose, a second start beside the one from a standing body (the better fit is
  // kept): the first tracked frame's pose, for a scan taken in the performer's first pose
  // (crouched, arms against the body) that a start from a standing body does not reach.
  std::optional<TemplatePose> first_tracked_pose;
  // With first_tracked_pose: the mean IoU of the template (the known shape) in a pose with the
  // first frame's masks in the tracking cameras. When the fit to the scan explains that frame's
  // silhouettes at least about as well as the tracked pose does, the scan stands in the first
  // frame's pose even where the tracked template lies far off it (a forearm folded the wrong way
  // at frame 0): the first frames ease from the fit (pipeline/first_pose_seam.h). Empty: the
  // residuals against the scan alone decide.
  std::function<double(const TemplatePose&)> first_frame_overlap;
  std::string given_path;   // correspondences to read and validate instead of placing; "": place
  std::string manual_path;  // with placement: pairs kept first, the automatic ones complete them
  double joint_clearance_m = CorrespondencePlacementOptions().joint_clearance_m;
};

struct ScanCorrespondence {
  ScanRegistration registration;    // with its warnings
  Mesh reference;                   // the template in the scan's pose, face labels = segments
  Correspondences correspondences;  // validated against `reference` and the scan
  bool given = false;               // read from options.given_path
  int num_manual = 0;               // manual pairs among them
};

// Registers `body` to `scan` (read from `scan_path`) and places or reads the pairs. With the
// first tracked pose, the registration is also started from it and the better fit kept; when
// that frame's template, unfitted, fits the scan about as well, segment by segment, it is the
// reference itself (the scan stands in the first frame's pose); when it does as a whole but a
// segment of it lies off the scan, the fit is the reference and registration.first_tracked_pose
// is set, for the deformation's seam (pipeline/first_pose_seam.h). When the seeded registrations
// fail, it is done from the scan alone (with a warning in registration.warnings). Throws
// InputError naming the scan or a correspondences file, UsageError for a bad option.
ScanCorrespondence CorrespondTemplateToScan(const BodyTemplate& body, const Mesh& scan, const std::string& scan_path,
                                            const ScanCorrespondenceOptions& options);

// Writes the reference template to `template_path` and the pairs, with the registration, to
// `correspondences_path`; the file names the scan (absolute) and the template as
// `template_reference` (e.g. relative to the file). Throws OutputError.
void WriteScanCorrespondence(const ScanCorrespondence& result, const BodyTemplate& body, const std::string& scan_path,
                             const std::string& template_path, const std::string& template_reference,
                             const std::string& correspondences_path);

}  // namespace confluent
