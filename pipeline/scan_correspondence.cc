#include "pipeline/scan_correspondence.h"

#include <filesystem>

#include "core/error.h"
#include "core/mesh_io.h"

namespace confluent {

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
    bool registered = false;
    if (options.first_tracked_pose) {
      // A scan in the performer's first pose: start there rather than from a standing body.
      ScanRegistrationOptions from_first_frame = registration_options;
      from_first_frame.initial_pose = options.first_tracked_pose;
      try {
        result.registration = RegisterTemplateToScan(body, scan, from_first_frame, scan_path);
        result.registration.warnings.push_back(std::string("the registration from the tracked shape failed (") +
                                               seeded_failure.what() +
                                               "); it was started from the first tracked frame's pose instead");
        registered = true;
      } catch (const InputError&) {
      }
    }
    if (!registered) {
      // The tracked shape or first pose can be poor (a coarse capture, an unusual first frame):
      // register as `confluent correspond` does, from the scan alone with the shape fitted. The
      // reference below keeps the tracked shape, which the tracked template meshes have.
      result.registration = RegisterTemplateToScan(body, scan, ScanRegistrationOptions(), scan_path);
      result.registration.warnings.push_back(std::string("the registration from the tracked shape and pose failed (") +
                                             seeded_failure.what() +
                                             "); the template was registered from the scan alone, its shape fitted");
    }
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
