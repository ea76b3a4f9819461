// confluent correspond: zero-click correspondences. The arguments of the registration and pair
// placement (pipeline/scan_correspondence.h), the report on the terminal, and the picture of the
// pairs (pipeline/pairs_picture.h).

#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "app/commands.h"
#include "core/body_segments.h"
#include "core/error.h"
#include "core/mesh_io.h"
#include "pipeline/pairs_picture.h"
#include "pipeline/scan_correspondence.h"
#include "tracking/body_template.h"
#include "tracking/motion_io.h"

namespace confluent::app {
namespace {

int RunCorrespond(const ParsedArgs& args, const Context& /*context*/) {
  std::string scan_path = args.get("scan");
  const std::string capture = args.get("capture");
  const std::string pose_path = args.get("template-pose");
  const std::string out_path = args.get("out");
  if (!capture.empty() && !pose_path.empty()) throw UsageError("give at most one of --capture and --template-pose");
  if (scan_path.empty()) {
    if (capture.empty()) throw UsageError("--scan S is required (or --capture CAPTURE with CAPTURE/scan.ply|obj)");
    for (const char* name : {"scan.ply", "scan.obj"})
      if (std::filesystem::exists(capture + "/" + name)) scan_path = capture + "/" + name;
    if (scan_path.empty()) throw InputError(capture, "no scan.ply or scan.obj in the capture folder");
  }
  const Mesh scan = ReadMesh(scan_path);
  const BodyTemplate body;

  ScanCorrespondenceOptions options;
  if (!pose_path.empty()) {
    const PosesFile poses = ReadPosesJson(pose_path, body);
    const int frame = args.get_int("pose-frame", 0);
    if (frame < 0 || frame >= static_cast<int>(poses.frames.size()))
      throw InputError(pose_path, "has no frame index " + std::to_string(frame) + " (" + std::to_string(poses.frames.size()) +
                                      " frames)");
    options.known_shape = poses.shape;
    options.initial_pose = poses.frames[frame].pose;
  }
  options.manual_path = args.get("manual");
  options.joint_clearance_m = args.get_double("joint-clearance", options.joint_clearance_m);
  if (!(options.joint_clearance_m >= 0)) throw UsageError("--joint-clearance: must be >= 0");
  ScanCorrespondence result = CorrespondTemplateToScan(body, scan, scan_path, options);
  const ScanRegistration& registration = result.registration;
  if (!pose_path.empty()) {
    // Reference-pose check against the tracked reference pose.
    const double tolerance_deg = ScanRegistrationOptions().reference_pose_tolerance_deg;
    const std::vector<double> difference =
        SegmentRotationDifferencesDeg(body, *options.known_shape, *options.initial_pose, registration.pose);
    for (int s = 0; s < kNumBodySegments; ++s)
      if (difference[s] > tolerance_deg) {
        char text[200];
        std::snprintf(text, sizeof text, "reference pose: segment %s of the scan differs by %.0f degrees from the tracked pose in %s",
                      BodySegmentName(s).c_str(), difference[s], pose_path.c_str());
        result.registration.warnings.push_back(text);
      }
  }
  const std::vector<std::string>& warnings = registration.warnings;
  const Correspondences& pairs = result.correspondences;
  const Mesh& template_mesh = result.reference;

  // Outputs: the posed template, the correspondences with the registration, the picture.
  const std::filesystem::path out(out_path);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  const std::string stem = (out.parent_path() / out.stem()).string();
  const std::string template_path = stem + "_template.ply";
  WriteScanCorrespondence(result, body, scan_path, template_path, std::filesystem::absolute(template_path).string(),
                          out_path);

  std::map<std::string, int> counts;
  const int num_manual = result.num_manual;
  for (const CorrespondencePair& p : pairs.pairs) ++counts[p.segment];
  std::printf("registration: rms residual %.4g, trimmed rms %.4g (scan units; %.3g m per unit), scan height %.4g\n",
              registration.rms_residual_m, registration.trimmed_rms_residual_m, registration.metres_per_unit,
              registration.scan_height);
  std::printf("%zu pairs (%d manual, %zu automatic) over %zu segments:\n", pairs.pairs.size(), num_manual,
              pairs.pairs.size() - num_manual, counts.size());
  for (int s = 0; s < kNumBodySegments; ++s) std::printf("  %-16s %d\n", BodySegmentName(s).c_str(), counts[BodySegmentName(s)]);
  for (const std::string& w : warnings) std::fprintf(stderr, "warning: %s: %s\n", scan_path.c_str(), w.c_str());
  const std::vector<std::string> empty = SegmentsWithoutPairs(pairs, [] {
    std::vector<std::string> names;
    for (int s = 0; s < kNumBodySegments; ++s) names.push_back(BodySegmentName(s));
    return names;
  }());
  for (const std::string& name : empty) std::fprintf(stderr, "warning: %s: segment %s has no pair\n", scan_path.c_str(), name.c_str());
  std::printf("wrote %s and %s\n", out_path.c_str(), template_path.c_str());

  const std::string picture = stem + "_pairs.png";
  try {
    WritePairsPicture(picture, template_mesh, scan, pairs, registration, body);
    std::printf("wrote %s\n", picture.c_str());
  } catch (const Error& e) {
    std::fprintf(stderr, "warning: picture not written: %s\n", e.what());
  }
  return 0;
}

}  // namespace

CommandSpec MakeCorrespondCommand() {
  CommandSpec spec;
  spec.name = "correspond";
  spec.summary = "register the template to a scan and place correspondences automatically";
  spec.usage = "--scan S [--capture CAPTURE | --template-pose FILE] [--manual FILE] --out FILE";
  spec.description =
      "Fits the body template's shape and pose to the scan (any orientation and unit; refuses "
      "scans that do not look human), places 140-220 template<->scan triangle pairs by segment "
      "(rings around the limbs, denser at shoulders and hips, away from the joints) and writes "
      "FILE (correspondences.json with the template registration), FILE-stem_template.ply (the "
      "posed template) and FILE-stem_pairs.png (both meshes side by side, pairs coloured by segment).";
  spec.options = {
      {"scan", "S", "scan mesh (.ply/.obj); default CAPTURE/scan.ply|obj"},
      {"capture", "CAPTURE", "capture folder (its scan is used when --scan is absent); shape fitted from the scan"},
      {"template-pose", "FILE", "poses.json of a track run: keep its shape, start from its pose (frame --pose-frame)"},
      {"pose-frame", "N", "frame index in --template-pose (default 0)"},
      {"manual", "FILE", "manual (or partial) correspondences.json to keep and complete"},
      {"joint-clearance", "M", "distance of the markers from the joints in metres (default 0.05)"},
      {"out", "FILE", "output correspondences.json", false, true},
  };
  spec.run = RunCorrespond;
  return spec;
}

}  // namespace confluent::app
