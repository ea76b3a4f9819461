#include "deform/correspondence_placement.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>

#include "core/body_model.h"
#include "core/body_segments.h"
#include "core/error.h"
#include "core/mesh_ops.h"

namespace confluent {

using Eigen::Vector3d;

void CorrespondencePlacementOptions::Check() const {
  const std::string owner = "CorrespondencePlacementOptions.";
  RequireOption(joint_clearance_m >= 0, owner + "joint_clearance_m", joint_clearance_m, ">= 0");
  RequireOption(metres_per_unit > 0, owner + "metres_per_unit", metres_per_unit, "> 0");
  RequireOption(limb_ring_markers >= 3, owner + "limb_ring_markers", limb_ring_markers, ">= 3");
  RequireOption(dense_ring_markers >= 3, owner + "dense_ring_markers", dense_ring_markers, ">= 3");
  RequireOption(max_pair_distance_m > 0, owner + "max_pair_distance_m", max_pair_distance_m, "> 0");
  RequireOption(max_normal_angle_deg > 0 && max_normal_angle_deg <= 180, owner + "max_normal_angle_deg",
                max_normal_angle_deg, "in (0, 180]");
  RequireOption(side_margin_m >= 0, owner + "side_margin_m", side_margin_m, ">= 0");
  for (double scale : joint_clearance_scales)
    RequireOption(scale >= 0, owner + "joint_clearance_scales", scale, ">= 0");
  RequireOption(manual_spacing_m >= 0, owner + "manual_spacing_m", manual_spacing_m, ">= 0");
}

void SetBodyJoints(const std::vector<Vector3d>& body_joints, CorrespondencePlacementOptions* options) {
  constexpr double kSpineClearanceScale = 2.0;
  options->joint_positions.clear();
  options->joint_clearance_scales.clear();
  for (int j = 0; j < static_cast<int>(body_joints.size()); ++j) {
    if (!JointJoinsSegments(j)) continue;
    options->joint_positions.push_back(body_joints[j]);
    options->joint_clearance_scales.push_back(j == kJointSpine ? kSpineClearanceScale : 1.0);
  }
}

namespace {

Vector3d FaceCentroid(const Mesh& mesh, int f) {
  return (mesh.vertices.row(mesh.faces(f, 0)) + mesh.vertices.row(mesh.faces(f, 1)) + mesh.vertices.row(mesh.faces(f, 2)))
             .transpose() / 3.0;
}

// Signed ray parameter of the intersection of the line origin + t * direction with face f
// (Moeller and Trumbore 1997), or NaN when the line misses it.
double LineHit(const Mesh& mesh, int f, const Vector3d& origin, const Vector3d& direction) {
  const Vector3d p0 = mesh.vertices.row(mesh.faces(f, 0));
  const Vector3d e1 = Vector3d(mesh.vertices.row(mesh.faces(f, 1))) - p0;
  const Vector3d e2 = Vector3d(mesh.vertices.row(mesh.faces(f, 2))) - p0;
  const Vector3d p = direction.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-300) return std::numeric_limits<double>::quiet_NaN();
  const double inv = 1.0 / det;
  const Vector3d s = origin - p0;
  const double u = s.dot(p) * inv;
  if (u < 0.0 || u > 1.0) return std::numeric_limits<double>::quiet_NaN();
  const Vector3d q = s.cross(e1);
  const double v = direction.dot(q) * inv;
  if (v < 0.0 || u + v > 1.0) return std::numeric_limits<double>::quiet_NaN();
  return e2.dot(q) * inv;
}

// A segment's geometry: faces, centroid, axis (pointing away from the body centre), a
// perpendicular frame and its extent along the axis.
struct SegmentGeometry {
  std::vector<int> faces;
  Vector3d centroid = Vector3d::Zero(), axis = Vector3d::UnitZ(), e1 = Vector3d::UnitX(), e2 = Vector3d::UnitY();
  double z_lo = 0, z_hi = 0, radius = 0;
};

// Markers per ring, from the ring nearest the body centre to the farthest; 0 = dense ring.
std::vector<int> RingPlan(int segment, const CorrespondencePlacementOptions& o) {
  const int L = o.limb_ring_markers, D = o.dense_ring_markers;
  switch (static_cast<BodySegment>(segment)) {
    case BodySegment::kHead: return {L + 2};
    case BodySegment::kNeck: return {L};
    case BodySegment::kUpperTorso: return {L + 2, D};          // dense at the shoulders
    case BodySegment::kLowerTorso: return {L + 2, D};          // dense at the hips
    case BodySegment::kLeftThigh:
    case BodySegment::kRightThigh: return {(L + D) / 2, L};    // denser at the lap
    case BodySegment::kLeftHand:
    case BodySegment::kRightHand:
    case BodySegment::kLeftFoot:
    case BodySegment::kRightFoot: return {L};
    default: return {L, L};
  }
}

}  // namespace

Correspondences PlaceCorrespondences(const Mesh& template_mesh, const Mesh& scan, const CorrespondencePlacementOptions& options,
                                     const Correspondences* manual) {
  options.Check();
  if (!template_mesh.has_face_labels()) throw InputError("template", "needs face labels (body segment ids) for placement");
  if (scan.num_faces() == 0) throw InputError("scan", "has no triangles");
  const double unit = 1.0 / options.metres_per_unit;  // mesh units per metre
  const double clearance = options.joint_clearance_m * unit;
  const double max_distance = options.max_pair_distance_m * unit;
  const double min_cos = std::cos(options.max_normal_angle_deg * M_PI / 180.0);
  const int nt = template_mesh.num_faces();
  const RowMatrixX3d template_normals = FaceNormals(template_mesh);
  const RowMatrixX3d scan_normals = FaceNormals(scan);
  std::vector<Vector3d> template_centroids(nt), scan_centroids(scan.num_faces());
  for (int f = 0; f < nt; ++f) template_centroids[f] = FaceCentroid(template_mesh, f);
  for (int f = 0; f < scan.num_faces(); ++f) scan_centroids[f] = FaceCentroid(scan, f);

  // Segment geometry.
  std::vector<SegmentGeometry> segments(kNumBodySegments);
  for (int f = 0; f < nt; ++f) {
    const int s = template_mesh.face_labels[f];
    if (s >= 0 && s < kNumBodySegments) segments[s].faces.push_back(f);
  }
  auto mean_of = [&](std::initializer_list<BodySegment> list) {
    Vector3d sum = Vector3d::Zero();
    int n = 0;
    for (BodySegment b : list)
      for (int f : segments[int(b)].faces) {
        sum += template_centroids[f];
        ++n;
      }
    return n ? Vector3d(sum / n) : Vector3d::Zero();
  };
  const Vector3d body_centre = mean_of({BodySegment::kUpperTorso, BodySegment::kLowerTorso});
  Vector3d up = mean_of({BodySegment::kHead}) - mean_of({BodySegment::kLowerTorso});
  up = up.norm() > 0 ? Vector3d(up.normalized()) : Vector3d::UnitZ();
  Vector3d lateral = mean_of({BodySegment::kLeftUpperArm, BodySegment::kLeftThigh, BodySegment::kLeftShank}) -
                     mean_of({BodySegment::kRightUpperArm, BodySegment::kRightThigh, BodySegment::kRightShank});
  lateral -= up * up.dot(lateral);
  lateral = lateral.norm() > 0 ? Vector3d(lateral.normalized()) : Vector3d(up.unitOrthogonal());
  for (int s = 0; s < kNumBodySegments; ++s) {
    SegmentGeometry& g = segments[s];
    if (g.faces.empty()) continue;
    for (int f : g.faces) g.centroid += template_centroids[f];
    g.centroid /= g.faces.size();
    const bool trunk = s == int(BodySegment::kHead) || s == int(BodySegment::kNeck) ||
                       s == int(BodySegment::kUpperTorso) || s == int(BodySegment::kLowerTorso);
    if (trunk) {
      g.axis = up;
    } else {
      Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
      for (int f : g.faces) c += (template_centroids[f] - g.centroid) * (template_centroids[f] - g.centroid).transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(c);
      g.axis = eigen.eigenvectors().col(2).normalized();
    }
    if ((g.centroid - body_centre).dot(g.axis) < 0) g.axis = -g.axis;
    Vector3d e1 = lateral - g.axis * g.axis.dot(lateral);
    if (e1.norm() < 0.3) e1 = up.cross(lateral) - g.axis * g.axis.dot(up.cross(lateral));
    g.e1 = e1.normalized();
    g.e2 = g.axis.cross(g.e1);
    g.z_lo = std::numeric_limits<double>::infinity();
    g.z_hi = -g.z_lo;
    double radius_sum = 0;
    for (int f : g.faces) {
      const Vector3d v = template_centroids[f] - g.centroid;
      const double z = v.dot(g.axis);
      g.z_lo = std::min(g.z_lo, z);
      g.z_hi = std::max(g.z_hi, z);
      radius_sum += (v - g.axis * z).norm();
    }
    g.radius = radius_sum / g.faces.size();
  }
  std::vector<Vector3d> joints = options.joint_positions;
  if (joints.empty())
    for (const SegmentGeometry& g : segments) {
      if (g.faces.empty()) continue;
      const double inset = std::min(g.radius, 0.25 * (g.z_hi - g.z_lo));
      joints.push_back(g.centroid + g.axis * (g.z_lo + inset));
      joints.push_back(g.centroid + g.axis * (g.z_hi - inset));
    }

  // The result starts with the manual pairs.
  Correspondences result;
  std::set<int> used_template, used_scan;
  std::vector<Vector3d> manual_points;
  if (manual) {
    ValidateCorrespondences(*manual, nt, scan.num_faces(), "manual correspondences");
    for (CorrespondencePair pair : manual->pairs) {
      if (pair.segment.empty()) pair.segment = BodySegmentName(template_mesh.face_labels[pair.template_triangle]);
      used_template.insert(pair.template_triangle);
      used_scan.insert(pair.scan_triangle);
      manual_points.push_back(template_centroids[pair.template_triangle]);
      result.pairs.push_back(pair);
    }
    result.template_path = manual->template_path;
    result.scan_path = manual->scan_path;
  }

  // Is a template face usable as a marker: away from the joints, outward-facing and not
  // covered by another segment (an overlap at a joint, an arm against the torso)?
  auto usable = [&](int s, int f) {
    const SegmentGeometry& g = segments[s];
    const Vector3d& c = template_centroids[f];
    // Short segments (neck, hands, feet) keep some markers: the clearance is at most 15% of
    // the segment's extent.
    const double segment_clearance = std::min(clearance, 0.15 * (g.z_hi - g.z_lo));
    for (std::size_t k = 0; k < joints.size(); ++k) {
      const Vector3d v = c - joints[k];
      const double axial = v.dot(g.axis);
      const double radial = (v - g.axis * axial).norm();
      const double distance = radial < 1.5 * g.radius ? std::abs(axial) : v.norm();
      const double joint_scale = k < options.joint_clearance_scales.size() ? options.joint_clearance_scales[k] : 1.0;
      if (distance < segment_clearance * joint_scale) return false;
    }
    for (const Vector3d& m : manual_points)
      if ((m - c).norm() < options.manual_spacing_m * unit) return false;
    const Vector3d n = template_normals.row(f);
    if (n.isZero()) return false;
    // Covered: another segment's surface lies just outside along the normal. Buried: the face
    // lies inside another segment (the first surface of it along the normal is left, not
    // entered), as a torso's cap inside the other torso part, where no scan surface is near.
    const Vector3d origin = c + 1e-6 * unit * n;
    std::array<double, kNumBodySegments> nearest;
    std::array<bool, kNumBodySegments> leaving{};
    nearest.fill(std::numeric_limits<double>::infinity());
    for (int h = 0; h < nt; ++h) {
      const int other = template_mesh.face_labels[h];
      if (other == s) continue;
      const double t = LineHit(template_mesh, h, origin, n);
      if (!(t >= 0)) continue;
      if (t < 2.0 * max_distance) return false;
      if (other >= 0 && other < kNumBodySegments && t < nearest[other]) {
        nearest[other] = t;
        leaving[other] = template_normals.row(h).dot(n) > 0;
      }
    }
    return std::none_of(leaving.begin(), leaving.end(), [](bool inside) { return inside; });
  };

  const Vector3d scan_centre = body_centre;
  auto side_ok = [&](const Vector3d& on_template, const Vector3d& on_scan) {
    const double margin = options.side_margin_m * unit;
    const double a = (on_template - body_centre).dot(lateral), b = (on_scan - scan_centre).dot(lateral);
    return !(std::abs(a) > margin && std::abs(b) > margin && a * b < 0);
  };

  // The scan triangle paired with template face f: along the normal line (nearest hit within
  // max_distance, consistent normal and side), else the nearest consistent triangle.
  auto pair_with_scan = [&](int f) {
    const Vector3d c = template_centroids[f];
    const Vector3d n = template_normals.row(f);
    int best = -1;
    double best_t = std::numeric_limits<double>::infinity();
    for (int g = 0; g < scan.num_faces(); ++g) {
      if ((scan_centroids[g] - c).squaredNorm() > 4.0 * max_distance * max_distance) continue;
      const double t = LineHit(scan, g, c, n);
      if (!(std::abs(t) <= max_distance) || std::abs(t) >= best_t) continue;
      if (Vector3d(scan_normals.row(g)).dot(n) < min_cos || used_scan.count(g)) continue;
      if (!side_ok(c, c + t * n)) continue;
      best = g;
      best_t = std::abs(t);
    }
    if (best >= 0) return best;
    double best_d2 = max_distance * max_distance;
    for (int g = 0; g < scan.num_faces(); ++g) {
      const double d2 = (scan_centroids[g] - c).squaredNorm();
      if (d2 >= best_d2 || Vector3d(scan_normals.row(g)).dot(n) < min_cos || used_scan.count(g)) continue;
      if (!side_ok(c, scan_centroids[g])) continue;
      best = g;
      best_d2 = d2;
    }
    return best;
  };

  for (int s = 0; s < kNumBodySegments; ++s) {
    const SegmentGeometry& g = segments[s];
    if (g.faces.empty()) continue;
    std::vector<int> candidates;
    for (int f : g.faces)
      if (!used_template.count(f) && usable(s, f)) candidates.push_back(f);
    if (candidates.empty()) continue;
    double a_lo = std::numeric_limits<double>::infinity(), a_hi = -a_lo;
    for (int f : candidates) {
      const double z = (template_centroids[f] - g.centroid).dot(g.axis);
      a_lo = std::min(a_lo, z);
      a_hi = std::max(a_hi, z);
    }
    const std::vector<int> plan = RingPlan(s, options);
    const int rings = static_cast<int>(plan.size());
    const double band = rings > 1 ? (a_hi - a_lo) / (rings - 1) : std::max(a_hi - a_lo, 1e-9);
    for (int k = 0; k < rings; ++k) {
      const double z_ring = rings > 1 ? a_lo + (a_hi - a_lo) * k / (rings - 1) : 0.5 * (a_lo + a_hi);
      const int markers = plan[k];
      const double half_sector = std::cos(M_PI / markers);
      for (int m = 0; m < markers; ++m) {
        const double theta = 2.0 * M_PI * (m + 0.5 * (k % 2)) / markers;
        const Vector3d direction = std::cos(theta) * g.e1 + std::sin(theta) * g.e2;
        int chosen = -1;
        double chosen_cost = std::numeric_limits<double>::infinity();
        for (int f : candidates) {
          if (used_template.count(f)) continue;
          const Vector3d v = template_centroids[f] - g.centroid;
          const double z = v.dot(g.axis);
          if (std::abs(z - z_ring) > 0.5 * band + 1e-12 && rings > 1) continue;
          Vector3d radial = v - g.axis * z;
          if (radial.norm() <= 0) continue;
          const double cos_phi = radial.normalized().dot(direction);
          if (cos_phi < half_sector) continue;
          const double dz = (z - z_ring) / (0.25 * band + 1e-12);
          const double cost = dz * dz + 20.0 * (1.0 - cos_phi);
          if (cost < chosen_cost) {
            chosen_cost = cost;
            chosen = f;
          }
        }
        if (chosen < 0) continue;
        const int on_scan = pair_with_scan(chosen);
        used_template.insert(chosen);
        if (on_scan < 0) continue;
        used_scan.insert(on_scan);
        CorrespondencePair pair;
        pair.template_triangle = chosen;
        pair.scan_triangle = on_scan;
        pair.segment = BodySegmentName(s);
        result.pairs.push_back(pair);
      }
    }
  }
  return result;
}

}  // namespace confluent
