#include "pipeline/scan_correspondence.h"

#include <filesystem>

#include "core/error.h"
#include "core/mesh_io.h"

namespace confluent {

namespace {

// The registration from the tracked shape and pose failed with `failure`. A scan in the
// performer's first pose is started from the first tracked frame's pose; failing that (the
// tracked shape or pose can be poor: a coarse capture, an unusual first frame), the template is
// registered as `confluent correspond` does, from the scan alone with the shape fitted. The
// caller's reference keeps the tracked shape, which the tracked template meshes have.
ScanRegistration RegisterAfterSeededFailure(const BodyTemplate& body, const Mesh& scan, const std::string& scan_path,
                                            const ScanRegistrationOptions& seeded,
                                            const ScanCorrespondenceOptions& options, const std::string& failure) {
  if (options.first_tracked_pose) {
    ScanRegistrationOptions from_first_frame = seeded;
    from_first_frame.initial_pose = options.first_tracked_pose;
    try {
      ScanRegistration registration = RegisterTemplateToScan(body, scan, from_first_frame, scan_path);
      registration.warnings.push_back("the registration from the tracked shape failed (" + failure +
                                      "); it was started from the first tracked frame's pose instead");
      return registration;
    } catch (const InputError&) {
      // On to the scan alone.
    }
  }
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
  try {
    result.registration = RegisterTemplateToScan(body, scan, registration_options, scan_path);
  } catch (const InputError& seeded_failure) {
    if (!options.known_shape && !options.initial_pose) throw;
    result.registration = RegisterAfterSeededFailure(body, scan, scan_path, registration_options, options,
                                                     seeded_failure.what());
  }
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
  placement.joint_positions = body.JointPositions(shape, result.registration.pose);
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
