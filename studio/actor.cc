// The synthetic studio actor: its skeleton, BuildStudioActor (surface from actor_surface.cc,
// albedo from actor_albedo.cc) and the skinning weights.

#include "studio/actor.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <unordered_map>
#include <utility>

#include "core/error.h"
#include "studio/actor_internal.h"

namespace confluent {
namespace actor_internal {

const std::vector<Bone>& Bones() {
  static const std::vector<Bone> bones = {
      {kJointPelvis, kJointSpine, BodySegment::kLowerTorso},     {kJointSpine, kJointChest, BodySegment::kUpperTorso},
      {kJointChest, kJointNeck, BodySegment::kUpperTorso},       {kJointNeck, kJointHead, BodySegment::kNeck},
      {kJointHead, kJointHeadEnd, BodySegment::kHead},           {kJointChest, kJointLeftShoulder, BodySegment::kUpperTorso},
      {kJointLeftShoulder, kJointLeftElbow, BodySegment::kLeftUpperArm}, {kJointLeftElbow, kJointLeftWrist, BodySegment::kLeftForearm},
      {kJointLeftWrist, kJointLeftHandEnd, BodySegment::kLeftHand},    {kJointChest, kJointRightShoulder, BodySegment::kUpperTorso},
      {kJointRightShoulder, kJointRightElbow, BodySegment::kRightUpperArm}, {kJointRightElbow, kJointRightWrist, BodySegment::kRightForearm},
      {kJointRightWrist, kJointRightHandEnd, BodySegment::kRightHand},   {kJointPelvis, kJointLeftHip, BodySegment::kLowerTorso},
      {kJointLeftHip, kJointLeftKnee, BodySegment::kLeftThigh},        {kJointLeftKnee, kJointLeftAnkle, BodySegment::kLeftShank},
      {kJointLeftAnkle, kJointLeftToe, BodySegment::kLeftFoot},        {kJointPelvis, kJointRightHip, BodySegment::kLowerTorso},
      {kJointRightHip, kJointRightKnee, BodySegment::kRightThigh},       {kJointRightKnee, kJointRightAnkle, BodySegment::kRightShank},
      {kJointRightAnkle, kJointRightToe, BodySegment::kRightFoot},
  };
  return bones;
}

// Distance from p to the segment [a, b] and the parameter of the closest point.
double SegmentDistance(const Vector3d& p, const Vector3d& a, const Vector3d& b, double* t_out = nullptr) {
  const Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  if (t_out) *t_out = t;
  return (p - (a + t * ab)).norm();
}

}  // namespace actor_internal

using namespace actor_internal;

namespace {

// Skinning weights: for each vertex, the bones adjacent to its nearest bone compete by
// distance; weights per driving joint are diffused over the mesh and cut to 4 influences.
SkinWeights ComputeWeights(const Mesh& mesh, const Adjacency& adjacency, const std::vector<Vector3d>& J,
                           const std::vector<BodySegment>& vertex_segment, double s) {
  const auto& bones = Bones();
  const int n = mesh.num_vertices();
  const int nb = static_cast<int>(bones.size());
  const double sigma = 0.03 * s;
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(n, kNumBodyJoints);
  std::vector<double> d(nb);
  for (int v = 0; v < n; ++v) {
    const Vector3d p = mesh.vertices.row(v).transpose();
    int primary = -1;
    for (int b = 0; b < nb; ++b) {
      d[b] = SegmentDistance(p, J[bones[b].from], J[bones[b].to]);
      if (bones[b].segment == vertex_segment[v] && (primary < 0 || d[b] < d[primary])) primary = b;
    }
    for (int b = 0; b < nb; ++b) {
      const Bone& pb = bones[primary];
      const bool adjacent = bones[b].from == pb.from || bones[b].from == pb.to || bones[b].to == pb.from ||
                            bones[b].to == pb.to;
      if (!adjacent) continue;
      const double x = std::max(0.0, d[b] - d[primary]) / sigma;
      w(v, bones[b].from) = std::max(w(v, bones[b].from), std::exp(-x * x));
    }
    w.row(v) /= w.row(v).sum();
  }
  Eigen::MatrixXd next(n, kNumBodyJoints);
  for (int it = 0; it < 4; ++it) {
    for (int v = 0; v < n; ++v) {
      Eigen::RowVectorXd mean = w.row(v);
      const int begin = adjacency.offsets[v], end = adjacency.offsets[v + 1];
      for (int e = begin; e < end; ++e) mean += w.row(adjacency.neighbors[e]);
      next.row(v) = mean / (1 + end - begin);
    }
    w.swap(next);
  }
  SkinWeights weights;
  weights.joints.setConstant(n, 4, -1);
  weights.weights.setZero(n, 4);
  for (int v = 0; v < n; ++v) {
    std::vector<int> order(kNumBodyJoints);
    std::iota(order.begin(), order.end(), 0);
    std::partial_sort(order.begin(), order.begin() + 4, order.end(), [&](int a, int b) { return w(v, a) > w(v, b); });
    double sum = 0.0;
    for (int k = 0; k < 4; ++k)
      if (w(v, order[k]) > 1e-3) sum += w(v, order[k]);
    for (int k = 0, slot = 0; k < 4; ++k)
      if (w(v, order[k]) > 1e-3) {
        weights.joints(v, slot) = order[k];
        weights.weights(v, slot++) = w(v, order[k]) / sum;
      }
  }
  return weights;
}

}  // namespace

void StudioActorOptions::Check() const {
  const std::string owner = "StudioActorOptions.";
  // The ranges also refuse NaN and infinity.
  RequireOption(height_m >= 0.5 && height_m <= 3.0, owner + "height_m", height_m, "in [0.5, 3] metres");
  const std::pair<const char*, double> factors[] = {
      {"torso_girth", torso_girth}, {"arm_girth", arm_girth}, {"leg_girth", leg_girth}, {"head_size", head_size}};
  for (const auto& [name, factor] : factors)
    RequireOption(factor >= 0.5 && factor <= 2.0, owner + name, factor, "in [0.5, 2]");
  RequireOption(arm_angle_deg >= 15.0 && arm_angle_deg <= 80.0, owner + "arm_angle_deg", arm_angle_deg, "in [15, 80]");
  RequireOption(target_triangles >= 2000 && target_triangles <= 5000000, owner + "target_triangles", target_triangles,
                "in [2000, 5000000]");
  RequireOption(smoothing_iterations >= 0 && smoothing_iterations <= 200, owner + "smoothing_iterations",
                smoothing_iterations, "in [0, 200]");
}

Skeleton MakeStudioSkeleton(const StudioActorOptions& options) {
  options.Check();
  const double s = options.height_m / 1.75;
  const std::array<Vector3d, kNumBodyJoints> rest = BodyRestPositions(options.arm_angle_deg * M_PI / 180.0);
  const std::array<int, kNumBodyJoints>& parents = BodyJointParents();
  const std::vector<std::string>& names = BodyJointNames();
  Skeleton skeleton;
  for (int j = 0; j < kNumBodyJoints; ++j) {
    Joint joint;
    joint.name = names[j];
    joint.parent = parents[j];
    joint.offset_in_parent = (parents[j] < 0 ? rest[j] : Vector3d(rest[j] - rest[parents[j]])) * s;
    skeleton.joints.push_back(joint);
  }
  return skeleton;
}

StudioActor BuildStudioActor(const StudioActorOptions& options) {
  options.Check();
  const double s = options.height_m / 1.75;
  StudioActor actor;
  actor.skeleton = MakeStudioSkeleton(options);
  const std::vector<Vector3d> J = actor.skeleton.RestPositions();
  const std::vector<Primitive> prims = BodyPrimitives(J, options);
  // Marching tetrahedra gives about 2.3e-3 m^2 * (triangles per m^2 ...): calibrated so that
  // triangles ~= kTrianglesCellSquared / cell^2 for the default build.
  const double kTrianglesCellSquared = 15.5;  // triangles * cell^2 (m^2) for the default body
  const double girth = (options.torso_girth + options.arm_girth + options.leg_girth) / 3.0;
  const double cell = std::sqrt(kTrianglesCellSquared * s * s * girth / options.target_triangles);
  // Keep every part at least 2 cells thick so that coarse meshes stay in one piece.
  std::vector<Primitive> meshed = prims;
  for (auto& prim : meshed) {
    const double r_min = cell;
    prim.r_a = prim.r_a.cwiseMax(r_min);
    prim.r_b = prim.r_b.cwiseMax(r_min);
    prim.cap_a = std::max(prim.cap_a, r_min);
    prim.cap_b = std::max(prim.cap_b, r_min);
  }
  Grid grid = SampleField(meshed, cell);
  Mesh mesh = MarchingTetrahedra(grid);
  std::vector<float>().swap(grid.values);
  KeepLargestComponent(&mesh);
  const Adjacency adjacency = VertexAdjacency(mesh);
  TaubinSmooth(adjacency, options.smoothing_iterations, &mesh.vertices);
  // Segments: the primitive that is closest (most inside) at each vertex.
  const int n = mesh.num_vertices();
  std::vector<BodySegment> vertex_segment(n);
  for (int v = 0; v < n; ++v) {
    const Vector3d p = mesh.vertices.row(v).transpose();
    double best = 1e9;
    for (const auto& prim : prims) {
      const double d = prim.Distance(p);
      if (d < best) {
        best = d;
        vertex_segment[v] = prim.segment;
      }
    }
  }
  mesh.face_labels.resize(mesh.num_faces());
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const BodySegment a = vertex_segment[mesh.faces(f, 0)], b = vertex_segment[mesh.faces(f, 1)],
                      c = vertex_segment[mesh.faces(f, 2)];
    mesh.face_labels[f] = static_cast<int>(b == c ? b : a);
  }
  mesh.colors.resize(n, 3);
  for (int v = 0; v < n; ++v)
    mesh.colors.row(v) =
        Albedo(mesh.vertices.row(v).transpose(), vertex_segment[v], J, s, options.seed).cast<float>().transpose();
  actor.weights = ComputeWeights(mesh, adjacency, J, vertex_segment, s);
  actor.mesh = std::move(mesh);
  actor.segment_joint = StudioSegmentJoints();
  return actor;
}

std::array<int, kNumBodySegments> StudioSegmentJoints() {
  return {kJointHead, kJointNeck, kJointSpine, kJointPelvis, kJointLeftShoulder, kJointLeftElbow, kJointLeftWrist, kJointRightShoulder,
          kJointRightElbow, kJointRightWrist, kJointLeftHip, kJointLeftKnee, kJointLeftAnkle, kJointRightHip, kJointRightKnee, kJointRightAnkle};
}

}  // namespace confluent
