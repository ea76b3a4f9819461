// confluent correspond: zero-click correspondences (issue 7). Registers the body template to the
// scan (tracking/scan_registration.h), places the template <-> scan triangle pairs
// (deform/correspondence_placement.h), writes correspondences.json with the registration, the
// posed template mesh and a picture of both meshes with the pairs coloured by segment.

#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "app/commands.h"
#include "calib/camera.h"
#include "core/body_segments.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "deform/correspondence_placement.h"
#include "deform/correspondences.h"
#include "render/renderer.h"
#include "tracking/body_template.h"
#include "tracking/motion_io.h"
#include "tracking/scan_registration.h"

namespace confluent::app {
namespace {

// A distinct colour per body segment (linear RGB).
Eigen::Vector3f SegmentColor(int segment) {
  static const float palette[kNumBodySegments][3] = {
      {0.90f, 0.10f, 0.10f}, {0.95f, 0.55f, 0.05f}, {0.95f, 0.90f, 0.05f}, {0.55f, 0.35f, 0.10f},
      {0.10f, 0.75f, 0.10f}, {0.05f, 0.45f, 0.05f}, {0.50f, 0.95f, 0.50f}, {0.10f, 0.30f, 0.95f},
      {0.05f, 0.10f, 0.45f}, {0.50f, 0.70f, 1.00f}, {0.75f, 0.10f, 0.85f}, {0.40f, 0.05f, 0.45f},
      {0.95f, 0.55f, 0.95f}, {0.05f, 0.80f, 0.80f}, {0.02f, 0.40f, 0.40f}, {0.60f, 0.95f, 0.95f}};
  if (segment < 0 || segment >= kNumBodySegments) return Eigen::Vector3f(0.3f, 0.3f, 0.3f);
  return Eigen::Vector3f(palette[segment][0], palette[segment][1], palette[segment][2]);
}

// `mesh` in the template's canonical frame (pelvis at the origin, facing +y, z up, metres),
// shifted by `offset`, with per-vertex colours.
Mesh Canonical(const Mesh& mesh, const Eigen::Isometry3d& canonical_from_scan, double metres_per_unit,
               const Eigen::Vector3d& offset) {
  Mesh out = mesh;
  for (int v = 0; v < out.num_vertices(); ++v)
    out.vertices.row(v) = (canonical_from_scan * Eigen::Vector3d(mesh.vertices.row(v).transpose()) * metres_per_unit + offset).transpose();
  out.face_labels.clear();
  out.uvs.resize(0, 2);
  out.face_uvs.resize(0, 3);
  out.texture_path.clear();
  return out;
}

// The picture: the template (left) and the scan (right) seen from the front, the paired
// triangles coloured by segment (on the scan, a small disc around each paired triangle).
void WritePairsPicture(const std::string& path, const Mesh& template_mesh, const Mesh& scan, const Correspondences& pairs,
                       const ScanRegistration& registration, const BodyTemplate& body) {
  const double mpu = registration.metres_per_unit;
  // canonical_from_scan: the inverse of the registered root transform (rotation about the pelvis).
  const Eigen::Matrix3d R = Eigen::AngleAxisd(registration.pose.root_rotation.norm(),
                                              registration.pose.root_rotation.norm() > 0
                                                  ? Eigen::Vector3d(registration.pose.root_rotation.normalized())
                                                  : Eigen::Vector3d::UnitZ())
                                .toRotationMatrix();
  const Eigen::Vector3d pelvis = body.JointPositions(registration.shape, registration.pose)[0];
  Eigen::Isometry3d canonical_from_scan = Eigen::Isometry3d::Identity();
  canonical_from_scan.linear() = R.transpose();
  canonical_from_scan.translation() = -R.transpose() * pelvis;
  const double half_width = 0.75;
  // Template: unshared vertices so that each face has its own colour.
  Mesh t;
  t.vertices.resize(3 * template_mesh.num_faces(), 3);
  t.faces.resize(template_mesh.num_faces(), 3);
  t.colors.resize(3 * template_mesh.num_faces(), 3);
  std::map<int, int> template_segment;
  for (const CorrespondencePair& p : pairs.pairs) template_segment[p.template_triangle] = BodySegmentFromName(p.segment);
  for (int f = 0; f < template_mesh.num_faces(); ++f) {
    const auto it = template_segment.find(f);
    const int label = template_mesh.has_face_labels() ? template_mesh.face_labels[f] : -1;
    const Eigen::Vector3f color =
        it != template_segment.end() ? SegmentColor(it->second) : Eigen::Vector3f(0.2f * SegmentColor(label) + Eigen::Vector3f::Constant(0.55f));
    for (int k = 0; k < 3; ++k) {
      t.vertices.row(3 * f + k) = template_mesh.vertices.row(template_mesh.faces(f, k));
      t.faces(f, k) = 3 * f + k;
      t.colors.row(3 * f + k) = color.transpose();
    }
  }
  t = Canonical(t, canonical_from_scan, mpu, Eigen::Vector3d(half_width, 0, 0));  // image left (camera in front)
  Mesh s = Canonical(scan, canonical_from_scan, mpu, Eigen::Vector3d(-half_width, 0, 0));
  s.colors = RowMatrixX3f::Constant(s.num_vertices(), 3, 0.7f);
  const double radius2 = 0.02 * 0.02;
  for (const CorrespondencePair& p : pairs.pairs) {
    if (p.scan_triangle < 0 || p.scan_triangle >= s.num_faces()) continue;
    const Eigen::Vector3d c = (s.vertices.row(s.faces(p.scan_triangle, 0)) + s.vertices.row(s.faces(p.scan_triangle, 1)) +
                               s.vertices.row(s.faces(p.scan_triangle, 2))).transpose() / 3.0;
    const Eigen::Vector3f color = SegmentColor(BodySegmentFromName(p.segment));
    for (int v = 0; v < s.num_vertices(); ++v)
      if ((Eigen::Vector3d(s.vertices.row(v).transpose()) - c).squaredNorm() < radius2) s.colors.row(v) = color.transpose();
    for (int k = 0; k < 3; ++k) s.colors.row(s.faces(p.scan_triangle, k)) = color.transpose();
  }
  Eigen::AlignedBox3d box;
  for (const Mesh* m : {&t, &s})
    for (int v = 0; v < m->num_vertices(); ++v) box.extend(Eigen::Vector3d(m->vertices.row(v).transpose()));
  const int width = 1200, height = 900;
  const double extent = std::max(box.sizes().x() / width, box.sizes().z() / height) * 1.15;
  const double distance = 5.0;
  const double focal = distance / extent;
  const Eigen::Vector3d target = box.center();
  const Camera camera = LookAtCamera("pairs", target + Eigen::Vector3d(0, distance + 0.5 * box.sizes().y(), 0), target,
                                     width, height, focal);
  MeshRenderer renderer;
  renderer.AddMesh(t, "template");
  renderer.AddMesh(s, "scan");
  RenderRequest request;
  request.shading.background = Eigen::Vector3d(1, 1, 1);
  request.shading.light_direction_in_world = Eigen::Vector3d(0.2, 1.0, 0.6);
  request.shading.ambient = 0.45;
  request.shading.diffuse = 0.55;
  const RenderResult result = renderer.Render(camera, request);
  WriteImage(path, result.color);
}

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

  ScanRegistrationOptions options;
  BodyShape tracked_shape;
  TemplatePose tracked_pose;
  if (!pose_path.empty()) {
    const PosesFile poses = ReadPosesJson(pose_path, body);
    const int frame = args.get_int("pose-frame", 0);
    if (frame < 0 || frame >= static_cast<int>(poses.frames.size()))
      throw InputError(pose_path, "has no frame index " + std::to_string(frame) + " (" + std::to_string(poses.frames.size()) +
                                      " frames)");
    tracked_shape = poses.shape;
    tracked_pose = poses.frames[frame].pose;
    options.fit_shape = false;
    options.initial_shape = tracked_shape;
    options.initial_pose = tracked_pose;
  }
  const ScanRegistration registration = RegisterTemplateToScan(body, scan, options, scan_path);
  std::vector<std::string> warnings = registration.warnings;
  if (!pose_path.empty()) {
    // Reference-pose check against the tracked reference pose.
    const std::vector<double> difference = SegmentRotationDifferencesDeg(body, tracked_shape, tracked_pose, registration.pose);
    for (int s = 0; s < kNumBodySegments; ++s)
      if (difference[s] > options.reference_pose_tolerance_deg) {
        char text[200];
        std::snprintf(text, sizeof text, "reference pose: segment %s of the scan differs by %.0f degrees from the tracked pose in %s",
                      BodySegmentName(s).c_str(), difference[s], pose_path.c_str());
        warnings.push_back(text);
      }
  }
  const Mesh template_mesh = body.PosedMesh(registration.shape, registration.pose);

  Correspondences manual;
  const bool has_manual = args.has("manual");
  if (has_manual) {
    manual = ReadCorrespondences(args.get("manual"));
    ValidateCorrespondences(manual, template_mesh.num_faces(), scan.num_faces(), args.get("manual"));
  }
  CorrespondencePlacementOptions placement;
  placement.metres_per_unit = registration.metres_per_unit;
  placement.joint_clearance_m = args.get_double("joint-clearance", placement.joint_clearance_m);
  if (!(placement.joint_clearance_m >= 0)) throw UsageError("--joint-clearance: must be >= 0");
  placement.joint_positions = body.JointPositions(registration.shape, registration.pose);
  Correspondences pairs = PlaceCorrespondences(template_mesh, scan, placement, has_manual ? &manual : nullptr);
  ValidateCorrespondences(pairs, template_mesh.num_faces(), scan.num_faces(), out_path);

  // Outputs: the posed template, the correspondences with the registration, the picture.
  const std::filesystem::path out(out_path);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  const std::string stem = (out.parent_path() / out.stem()).string();
  const std::string template_path = stem + "_template.ply";
  WriteMesh(template_path, template_mesh);
  pairs.template_path = std::filesystem::absolute(template_path).string();
  pairs.scan_path = std::filesystem::absolute(scan_path).string();
  WriteCorrespondences(out_path, pairs);
  ScanRegistration written = registration;
  written.warnings = warnings;
  WriteTemplateRegistration(out_path, body, written);

  std::map<std::string, int> counts;
  int num_manual = has_manual ? static_cast<int>(manual.pairs.size()) : 0;
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
