#include "pipeline/scan_correspondence.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "core/mesh_io.h"

namespace confluent {

namespace {

// The first tracked frame's template is kept as the scan's reference pose when its residual is
// within this factor of the fitted registration's, and no segment of it is further than
// kAsTrackedSegmentExcessM off the scan than the fit's (a tracked arm 2 cm off a scan that the
// body as a whole fits well is an error of the tracker, not the scan's pose).
constexpr double kAsTrackedTolerance = 1.25;
constexpr double kAsTrackedSegmentExcessM = 0.01;
// The first frame's mean silhouette IoU that the fit may fall short of the tracked pose's and
// still count as that frame's pose (ScanCorrespondenceOptions::first_frame_overlap).
constexpr double kFirstFrameIouTolerance = 0.005;

// The segment of `a` whose rms exceeds `b`'s the most, and by how much (metres).
struct SegmentExcess {
  int segment = -1;
  double metres = 0.0;
};
SegmentExcess WorstSegmentExcess(const ScanRegistration& a, const ScanRegistration& b) {
  SegmentExcess worst;
  for (std::size_t s = 0; s < a.segment_rms_m.size() && s < b.segment_rms_m.size(); ++s)
    if (std::isfinite(a.segment_rms_m[s]) && std::isfinite(b.segment_rms_m[s]) &&
        (a.segment_rms_m[s] - b.segment_rms_m[s]) * a.metres_per_unit > worst.metres)
      worst = {static_cast<int>(s), (a.segment_rms_m[s] - b.segment_rms_m[s]) * a.metres_per_unit};
  return worst;
}

std::string Centimetres(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f cm", 100.0 * metres);
  return text;
}

// The registration seeded by the tracked shape (and pose, when given). When the first tracked
// frame's pose is known, the registration is also started from it and the one that fits the scan
// better is kept: a scan taken in the performer's first pose (crouched, arms against the body) is
// reached from there, not from a standing body, and registered so, its frame 0 is the scan itself.
// When neither start gives a human-like fit (the tracked shape or pose can be poor: a coarse
// capture, an unusual first frame), the template is registered as `confluent correspond` does,
// from the scan alone with the shape fitted; the caller's reference keeps the tracked shape.
ScanRegistration RegisterSeeded(const BodyTemplate& body, const Mesh& scan, const std::string& scan_path,
                                const ScanRegistrationOptions& seeded, const ScanCorrespondenceOptions& options) {
  std::optional<ScanRegistration> from_seed, from_first_frame;
  std::string failure;
  try {
    from_seed = RegisterTemplateToScan(body, scan, seeded, scan_path);
  } catch (const InputError& e) {
    if (!options.known_shape && !options.initial_pose) throw;
    failure = e.what();
  }
  std::optional<ScanRegistration> as_tracked;
  if (options.first_tracked_pose && !options.initial_pose) {
    ScanRegistrationOptions first = seeded;
    first.initial_pose = options.first_tracked_pose;
    try {
      from_first_frame = RegisterTemplateToScan(body, scan, first, scan_path);
      first.rounds = 0;  // the first tracked frame's template as it is
      as_tracked = RegisterTemplateToScan(body, scan, first, scan_path);
    } catch (const InputError&) {
      // The scan is not in the first frame's pose (or not in the capture's frame).
    }
  }
  const bool first_fits_better =
      from_first_frame && (!from_seed || from_first_frame->rms_residual_m < from_seed->rms_residual_m);
  // The scan stands in the first frame's pose, and the tracked template fits it about as well as
  // a fit to the scan does: frame 0's template itself is the reference, so that frame 0 of the
  // animated scan is the scan and later frames move by what the tracker saw move.
  ScanRegistration* const fitted = first_fits_better ? &*from_first_frame : from_seed ? &*from_seed : nullptr;
  const double fitted_rms = fitted ? fitted->rms_residual_m : 0.0;
  const bool in_first_pose = as_tracked && as_tracked->rms_residual_m <= kAsTrackedTolerance * fitted_rms;
  const SegmentExcess excess = in_first_pose ? WorstSegmentExcess(*as_tracked, *fitted) : SegmentExcess();
  if (in_first_pose && excess.metres <= kAsTrackedSegmentExcessM) {
    as_tracked->warnings.push_back("the scan stands in the first tracked frame's pose: that frame's template is the "
                                   "reference (rms " + Centimetres(as_tracked->rms_residual_m) + ", fitted " +
                                   Centimetres(fitted_rms) + ")");
    return *as_tracked;
  }
  if (in_first_pose) {
    // The tracker erred on one segment at frame 0: the fit is the reference, and the first frames
    // ease from it into the tracked poses (pipeline/first_pose_seam.h).
    fitted->first_tracked_pose = options.first_tracked_pose;
    fitted->warnings.push_back("the scan stands in the first tracked frame's pose, but that frame's " +
                               BodySegmentName(excess.segment) + " is " + Centimetres(excess.metres) +
                               " further off the scan than a fit's: the fit is the reference, and the first frames "
                               "ease from it into the tracked poses");
  } else if (fitted && options.first_tracked_pose && options.first_frame_overlap) {
    // The tracked template lies too far off the scan to call it the scan's pose by the residuals
    // (a whole limb wrong), but the first frame's silhouettes may still say that the scan's pose,
    // not the tracked one, is what the cameras saw.
    const double fitted_iou = options.first_frame_overlap(fitted->pose);
    const double tracked_iou = options.first_frame_overlap(*options.first_tracked_pose);
    if (fitted_iou >= tracked_iou - kFirstFrameIouTolerance) {
      char ious[64];
      std::snprintf(ious, sizeof ious, "mean IoU %.4f, tracked %.4f", fitted_iou, tracked_iou);
      const std::string line = "the fit to the scan explains the first frame's silhouettes as well as that frame's "
                               "tracked pose (" + std::string(ious) + "): the scan stands in the first frame's pose, "
                               "the fit is the reference, and the first frames ease from it into the tracked poses";
      fitted->first_tracked_pose = options.first_tracked_pose;
      fitted->warnings.push_back(line);
    }
  }
  if (first_fits_better) {
    from_first_frame->warnings.push_back(
        from_seed ? "the template was registered from the first tracked frame's pose: it fits the scan better "
                    "(rms " + Centimetres(fitted_rms) + ", against " + Centimetres(from_seed->rms_residual_m) +
                        " from a standing body)"
                  : "the registration from the tracked shape failed (" + failure +
                        "); it was started from the first tracked frame's pose instead");
    return *from_first_frame;
  }
  if (from_seed) return *from_seed;
  ScanRegistration registration = RegisterTemplateToScan(body, scan, ScanRegistrationOptions(), scan_path);
  registration.warnings.push_back("the registration from the tracked shape and pose failed (" + failure +
                                  "); the template was registered from the scan alone, its shape fitted");
  return registration;
}

}  // namespace

ScanCorrespondence CorrespondTemplateToScan(const BodyTemplate& body, const Mesh& scan, const std::string& scan_path,
                                            const ScanCorrespondenceOptions& options) {
  RequireOption(options.joint_clearance_m >= 0.0, "ScanCorrespondenceOptions.joint_clearance_m",
                options.joint_clearance_m, ">= 0");
  ScanCorrespondence result;
  ScanRegistrationOptions registration_options;
  if (options.known_shape) {
    registration_options.fit_shape = false;
    registration_options.initial_shape = *options.known_shape;
  }
  registration_options.initial_pose = options.initial_pose;
  result.registration = RegisterSeeded(body, scan, scan_path, registration_options, options);
  const BodyShape& shape = options.known_shape ? *options.known_shape : result.registration.shape;
  result.reference = body.PosedMesh(shape, result.registration.pose);
  const int template_faces = result.reference.num_faces(), scan_faces = scan.num_faces();

  if (!options.given_path.empty()) {
    result.correspondences = ReadCorrespondences(options.given_path);
    ValidateCorrespondences(result.correspondences, template_faces, scan_faces, options.given_path);
    result.given = true;
    return result;
  }
  Correspondences manual;
  if (!options.manual_path.empty()) {
    manual = ReadCorrespondences(options.manual_path);
    ValidateCorrespondences(manual, template_faces, scan_faces, options.manual_path);
    result.num_manual = static_cast<int>(manual.pairs.size());
  }
  CorrespondencePlacementOptions placement;
  placement.joint_clearance_m = options.joint_clearance_m;
  placement.metres_per_unit = result.registration.metres_per_unit;
  SetBodyJoints(body.JointPositions(shape, result.registration.pose), &placement);
  result.correspondences =
      PlaceCorrespondences(result.reference, scan, placement, options.manual_path.empty() ? nullptr : &manual);
  ValidateCorrespondences(result.correspondences, template_faces, scan_faces, scan_path);
  return result;
}

void WriteScanCorrespondence(const ScanCorrespondence& result, const BodyTemplate& body, const std::string& scan_path,
                             const std::string& template_path, const std::string& template_reference,
                             const std::string& correspondences_path) {
  WriteMesh(template_path, result.reference);
  Correspondences written = result.correspondences;
  written.scan_path = std::filesystem::absolute(scan_path).string();
  written.template_path = template_reference;
  WriteCorrespondences(correspondences_path, written);
  WriteTemplateRegistration(correspondences_path, body, result.registration);
}

}  // namespace confluent
