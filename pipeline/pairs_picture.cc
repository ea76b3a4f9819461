#include "pipeline/pairs_picture.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <map>

#include "calib/camera.h"
#include "core/body_segments.h"
#include "core/image_io.h"
#include "render/renderer.h"

namespace confluent {
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

}  // namespace

// On the scan, a small disc around each paired triangle carries the colour.
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

}  // namespace confluent
