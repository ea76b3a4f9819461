// Template-to-scan registration: the one translation unit with its Ceres cost functors (they
// compile slowly). Reading and writing the result is in registration_io.cc, pose-from-joints
// fitting in pose_from_joints.cc.

#include "tracking/scan_registration.h"

#include <ceres/ceres.h>
#include <ceres/normal_prior.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <numeric>
#include <random>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mesh_ops.h"
#include "tracking/body_model_impl.h"
#include "tracking/fit_params.h"
#include "tracking/pose_from_joints.h"
#include "tracking/scan_samples.h"

namespace confluent {

namespace ti = tracking_internal;
using Eigen::Matrix3d;
using Eigen::Vector3d;

void ScanRegistrationOptions::Check() const {
  const std::string owner = "ScanRegistrationOptions.";
  RequireOption(num_scan_samples >= 100, owner + "num_scan_samples", num_scan_samples, ">= 100");
  RequireOption(num_scan_residuals >= 50, owner + "num_scan_residuals", num_scan_residuals, ">= 50");
  RequireOption(rounds >= 0, owner + "rounds", rounds, ">= 0");
  RequireOption(max_iterations >= 1, owner + "max_iterations", max_iterations, ">= 1");
  RequireOption(min_pair_distance_m > 0, owner + "min_pair_distance_m", min_pair_distance_m, "> 0");
  RequireOptions(max_pair_distance_m >= min_pair_distance_m, owner + "min_pair_distance_m", min_pair_distance_m,
                 owner + "max_pair_distance_m", max_pair_distance_m, "min_pair_distance_m <= max_pair_distance_m");
  RequireOption(max_normal_angle_deg > 0 && max_normal_angle_deg <= 180, owner + "max_normal_angle_deg",
                max_normal_angle_deg, "in (0, 180]");
  RequireOption(loss_scale_m > 0, owner + "loss_scale_m", loss_scale_m, "> 0");
  RequireOption(prior_weight >= 0, owner + "prior_weight", prior_weight, ">= 0");
  RequireOption(shape_prior_weight >= 0, owner + "shape_prior_weight", shape_prior_weight, ">= 0");
  RequireOption(max_residual_fraction > 0, owner + "max_residual_fraction", max_residual_fraction, "> 0");
  RequireOption(reference_pose_tolerance_deg > 0, owner + "reference_pose_tolerance_deg", reference_pose_tolerance_deg,
                "> 0");
  RequireOption(num_threads >= 1, owner + "num_threads", num_threads, ">= 1");
}

namespace {

using ti::FitParams;
using ti::kShapeBlockSize;
using ti::ParamsToPose;
using ti::ParamsToShape;
using ti::PoseToParams;
using ti::SegmentChains;
using ti::SegmentsInWorld;
using ti::TemplateFitSolverOptions;
using ti::SegmentWorld;
using ti::ShapeArrays;
using ti::ShapeToParams;
using ti::KdTree;
using ti::ScanSamples;
using ti::SampleScan;

// ---------------------------------------------------------------------------------------------
// Parameters and the template's segments in the world.

// Approximate signed distance of a point to a segment capsule (negative inside) from its
// normalised capsule coordinates; `normal` receives the outward direction.
template <typename T>
T CapsuleDistance(const ti::SegmentFrame<T>& f, const ti::Vec3<T>& a, const ti::Vec3<T>& axis, const ti::Vec3<T>& e1,
                  const ti::Vec3<T>& e2, const ti::Vec3<T>& p, ti::Vec3<T>* normal) {
  using std::sqrt;
  const ti::Vec3<T> o = p - a;
  const T oz = o.dot(axis), ox = o.dot(e1), oy = o.dot(e2);
  T s = oz;
  if (s < T(0.0)) s = T(0.0);
  if (s > f.length) s = f.length;
  const T frac = s / f.length;
  T rx, ry;
  f.Radii(frac, &rx, &ry);
  const T over = oz - s;
  const T cap = over < T(0.0) ? f.cap_a : f.cap_b;
  const T qx = ox / rx, qy = oy / ry, qz = over / cap;
  const T nq = sqrt(qx * qx + qy * qy + qz * qz + T(1e-12));
  if (normal) {
    const ti::Vec3<T> g = e1 * (qx / rx) + e2 * (qy / ry) + axis * (qz / cap);
    *normal = g / sqrt(g.squaredNorm() + T(1e-24));
  }
  // Scale: the local radius in the direction of the point.
  const T radius = (over != T(0.0)) ? (rx + ry + cap) / T(3.0) : (rx + ry) / T(2.0);
  return (nq - T(1.0)) * radius;
}

// ---------------------------------------------------------------------------------------------
// The Ceres cost of one segment: template points -> paired scan samples (point-to-plane plus a
// weak tangential term) and scan samples -> the segment's capsule. Parameter blocks: root
// translation (3), root rotation vector (3), the DOF blocks of the joints on the segment's chain,
// then the shape block (20).
struct SurfaceCost {
  const BodyTemplate* body = nullptr;
  int segment = 0;
  Matrix3d root_reference = Matrix3d::Identity();
  std::vector<int> chain_joints;
  std::vector<SurfaceCoord> model_coords;       // template surface points paired with scan samples
  std::vector<Vector3d> targets, target_normals, tangent1, tangent2;
  std::vector<double> model_weights;
  std::vector<Vector3d> scan_points;            // scan samples paired with this segment
  std::vector<double> scan_weights;
  double tangential_weight = 0.3;
  ti::Section<double> section;                  // the segment's cross-section (held constant here)

  int num_residuals() const { return static_cast<int>(3 * model_coords.size() + scan_points.size()); }

  template <typename T>
  bool operator()(T const* const* p, T* residuals) const {
    const T* jp[kNumTemplateJoints] = {};
    for (std::size_t i = 0; i < chain_joints.size(); ++i) jp[chain_joints[i]] = p[2 + i];
    const T* shape = p[2 + chain_joints.size()];
    T length[kNumBodySegments], girth[kNumBodySegments];
    ShapeArrays(shape, length, girth);
    std::array<ti::Vec3<T>, kNumTemplateJoints> rest;
    ti::RestPositions(*body, length, girth, &rest);
    const ti::SegmentFrame<T> frame =
        ti::MakeSegmentFrame(*body, segment, rest, length, girth, static_cast<const T*>(nullptr),
                             ti::Section<T>{T(section.depth), T(section.taper), T(section.offset), T(section.bulge)});
    const int joint = body->segments()[segment].joint;
    ti::Mat3<T> R;
    ti::Vec3<T> P;
    ti::JointWorldTransform(*body, joint, rest, p[0], p[1], root_reference, jp, &R, &P);
    int r = 0;
    for (std::size_t i = 0; i < model_coords.size(); ++i) {
      const ti::Vec3<T> X = P + R * (frame.Point(model_coords[i]) - rest[joint]);
      const ti::Vec3<T> d = X - targets[i].cast<T>();
      const T w(model_weights[i]);
      residuals[r++] = w * d.dot(target_normals[i].cast<T>());
      residuals[r++] = w * T(tangential_weight) * d.dot(tangent1[i].cast<T>());
      residuals[r++] = w * T(tangential_weight) * d.dot(tangent2[i].cast<T>());
    }
    if (!scan_points.empty()) {
      const ti::Vec3<T> a = P + R * (frame.a - rest[joint]);
      const ti::Vec3<T> axis = R * frame.axis, e1 = R * frame.e1, e2 = R * frame.e2;
      for (std::size_t i = 0; i < scan_points.size(); ++i)
        residuals[r++] =
            T(scan_weights[i]) * CapsuleDistance<T>(frame, a, axis, e1, e2, scan_points[i].cast<T>(), nullptr);
    }
    return true;
  }
};

// One round's pairs and residual statistics.
struct Pairing {
  std::array<SurfaceCost, kNumBodySegments> costs;
  std::vector<double> distances;                       // all accepted distances (both directions)
  std::array<std::vector<double>, kNumBodySegments> segment_distances;  // template -> scan
  std::array<std::vector<Vector3d>, kNumBodySegments> scan_points;      // scan samples per segment
  double rms = 0.0, trimmed_rms = 0.0;
  int num_pairs = 0;
};

double Rms(std::vector<double> d, double keep_fraction) {
  if (d.empty()) return std::numeric_limits<double>::infinity();
  std::sort(d.begin(), d.end());
  const std::size_t n = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(keep_fraction * d.size())));
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i) sum += d[i] * d[i];
  return std::sqrt(sum / n);
}

// Pairs the template (at `fp`) with the scan. `max_distance` limits pairs (infinity: every
// template point and scan sample is paired, for the final statistics).
Pairing MakePairs(const BodyTemplate& body, const FitParams& fp, const ScanSamples& samples, const KdTree& tree,
                  const std::vector<int>& residual_samples, double max_distance, double min_cos, double loss_scale) {
  Pairing pairing;
  const auto segments = SegmentsInWorld(body, fp);
  const Mesh mesh = body.PosedMesh(ParamsToShape(fp.shape, nullptr, fp.section), ParamsToPose(fp));
  const RowMatrixX3d normals = VertexNormals(mesh);
  const int nv = static_cast<int>(body.mesh_coords().size());
  const bool unlimited = !std::isfinite(max_distance);
  auto huber = [&](double d) { return std::abs(d) <= loss_scale ? 1.0 : std::sqrt(loss_scale / std::abs(d)); };
  for (int s = 0; s < kNumBodySegments; ++s) pairing.costs[s].segment = s;
  // Template -> scan.
  for (int s = 0; s < kNumBodySegments; ++s) {
    SurfaceCost& cost = pairing.costs[s];
    for (int v = 0; v < nv; ++v) {
      const Vector3d X = mesh.vertices.row(s * nv + v);
      const Vector3d n = normals.row(s * nv + v);
      // Skip points inside another segment (the overlaps at the joints).
      bool inside = false;
      for (int o = 0; o < kNumBodySegments && !inside; ++o) {
        if (o == s) continue;
        const SegmentWorld& w = segments[o];
        inside = CapsuleDistance<double>(w.frame, w.a, w.axis, w.e1, w.e2, X, nullptr) < 0.0;
      }
      if (inside) continue;
      double d2;
      const int nearest = tree.Nearest(X, &d2);
      if (nearest < 0) continue;
      const Vector3d& q = samples.points[nearest];
      const Vector3d& nq = samples.normals[nearest];
      const Vector3d d = X - q;
      double distance = std::sqrt(d2);
      if (distance < 2.0 * samples.spacing) distance = std::abs(d.dot(nq));
      if (!unlimited && (distance > max_distance || n.dot(nq) < min_cos)) continue;
      pairing.distances.push_back(distance);
      pairing.segment_distances[s].push_back(distance);
      cost.model_coords.push_back(body.mesh_coords()[v]);
      cost.targets.push_back(q);
      cost.target_normals.push_back(nq);
      Vector3d t1 = nq.unitOrthogonal();
      cost.tangent1.push_back(t1);
      cost.tangent2.push_back(nq.cross(t1));
      cost.model_weights.push_back(huber(distance));
    }
  }
  // Scan -> template.
  for (int i : residual_samples) {
    const Vector3d& p = samples.points[i];
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (int s = 0; s < kNumBodySegments; ++s) {
      const SegmentWorld& w = segments[s];
      Vector3d normal;
      const double d = CapsuleDistance<double>(w.frame, w.a, w.axis, w.e1, w.e2, p, &normal);
      if (!unlimited && normal.dot(samples.normals[i]) < min_cos) continue;
      if (std::abs(d) < std::abs(best_d)) {
        best_d = d;
        best = s;
      }
    }
    if (best < 0 || (!unlimited && std::abs(best_d) > max_distance)) continue;
    pairing.distances.push_back(std::abs(best_d));
    pairing.costs[best].scan_points.push_back(p);
    pairing.costs[best].scan_weights.push_back(huber(best_d));
    pairing.scan_points[best].push_back(p);
  }
  pairing.num_pairs = static_cast<int>(pairing.distances.size());
  pairing.rms = Rms(pairing.distances, 1.0);
  pairing.trimmed_rms = Rms(pairing.distances, 0.9);
  return pairing;
}

// Score of a pairing for comparing hypotheses: trimmed rms with unpaired points counted at the
// pairing distance.
double HypothesisScore(const Pairing& pairing, int num_candidates, double max_distance) {
  std::vector<double> d = pairing.distances;
  while (static_cast<int>(d.size()) < num_candidates) d.push_back(max_distance);
  return Rms(d, 0.9);
}

// One Ceres solve on the given pairs.
void Solve(const BodyTemplate& body, Pairing* pairing, const ScanRegistrationOptions& options, bool rigid, bool fit_shape,
           double scale, const FitParams& prior, FitParams* fp) {
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  const auto chains = SegmentChains(body);
  for (int s = 0; s < kNumBodySegments; ++s) {
    SurfaceCost& source = pairing->costs[s];
    if (source.num_residuals() == 0) continue;
    auto* functor = new SurfaceCost(std::move(source));
    functor->body = &body;
    functor->root_reference = fp->root_reference;
    functor->chain_joints = chains[s];
    functor->section = ti::SegmentSection(fp->section, s);
    auto* cost = new ceres::DynamicAutoDiffCostFunction<SurfaceCost, 16>(functor);
    const std::vector<double*> blocks = ti::AddSegmentParameterBlocks(body, chains[s], fp, cost);
    cost->SetNumResiduals(functor->num_residuals());
    problem.AddResidualBlock(cost, nullptr, blocks);
  }
  if (problem.NumResidualBlocks() == 0) return;
  for (int j = 1; j < kNumTemplateJoints; ++j) {
    const int n = body.dofs()[j].num_dof();
    double* block = fp->dofs[j].data();
    if (n == 0 || !problem.HasParameterBlock(block)) continue;
    if (rigid) {
      problem.SetParameterBlockConstant(block);
      continue;
    }
    ti::AddJointPriorAndLimits(body, j, prior.dofs[j].data(), options.prior_weight * scale, block, &problem);
  }
  if (fit_shape && !rigid) {
    Eigen::MatrixXd A = Eigen::MatrixXd::Identity(kShapeBlockSize, kShapeBlockSize) * options.shape_prior_weight * scale;
    Eigen::VectorXd b(kShapeBlockSize);
    for (int i = 0; i < kShapeBlockSize; ++i) b(i) = prior.shape[i];
    // Prior towards a uniformly scaled body: the mean of the current lengths and girths.
    double mean_l = 0, mean_g = 0;
    for (int g = 0; g < ti::kNumShapeGroups; ++g) {
      mean_l += prior.shape[g] / ti::kNumShapeGroups;
      mean_g += prior.shape[ti::kNumShapeGroups + g] / ti::kNumShapeGroups;
    }
    for (int g = 0; g < ti::kNumShapeGroups; ++g) {
      b(g) = mean_l;
      b(ti::kNumShapeGroups + g) = mean_g;
    }
    problem.AddResidualBlock(new ceres::NormalPrior(A, b), nullptr, fp->shape);
    for (int i = 0; i < kShapeBlockSize; ++i) {
      problem.SetParameterLowerBound(fp->shape, i, 0.6 * b(i));
      problem.SetParameterUpperBound(fp->shape, i, 1.6 * b(i));
    }
  } else {
    problem.SetParameterBlockConstant(fp->shape);
  }
  const ceres::Solver::Options solver_options =
      TemplateFitSolverOptions(options.max_iterations, options.num_threads, 1e-6, 1e-7);
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  // Fold the root rotation increment into the reference.
  fp->root_reference = ti::AngleAxisMatrix(fp->root_aa) * fp->root_reference;
  fp->root_aa[0] = fp->root_aa[1] = fp->root_aa[2] = 0.0;
}

// The area-weighted centroid of a mesh.
Vector3d AreaCentroid(const Mesh& mesh) {
  const Eigen::VectorXd areas = FaceAreas(mesh);
  Vector3d sum = Vector3d::Zero();
  double total = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Vector3d c = (mesh.vertices.row(mesh.faces(f, 0)) + mesh.vertices.row(mesh.faces(f, 1)) +
                        mesh.vertices.row(mesh.faces(f, 2))).transpose() / 3.0;
    sum += areas(f) * c;
    total += areas(f);
  }
  return total > 0 ? Vector3d(sum / total) : Vector3d::Zero();
}

// A shoulder rotation vector that turns the rest upper arm of `shoulder` to `angle_deg` from the
// vertical, in the frontal plane.
std::array<double, 3> ArmAngle(const BodyTemplate& body, int shoulder, double angle_deg) {
  const Vector3d rest_dir = (body.generic_rest()[shoulder + 1] - body.generic_rest()[shoulder]).normalized();
  const double sx = rest_dir.x() < 0 ? -1.0 : 1.0;
  const double a = angle_deg * M_PI / 180.0;
  const Vector3d target(sx * std::sin(a), rest_dir.y(), -std::cos(a));
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(rest_dir, target.normalized());
  const Eigen::AngleAxisd aa(q);
  const Vector3d v = aa.angle() * aa.axis();
  return {v.x(), v.y(), v.z()};
}

std::string Fmt(const char* format, double a, double b = 0, double c = 0) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, format, a, b, c);
  return buffer;
}

double GuessMetresPerUnit(double height) {
  for (double unit : {1.0, 0.1, 0.01, 0.001, 0.0254})
    if (height * unit >= 0.9 && height * unit <= 2.5) return unit;
  return 1.0;
}

}  // namespace

ScanRegistration RegisterTemplateToScan(const BodyTemplate& body, const Mesh& scan, const ScanRegistrationOptions& options,
                                        const std::string& scan_source) {
  options.Check();
  if (scan.num_faces() == 0 || scan.num_vertices() < 4) throw InputError(scan_source, "the scan has no triangles");
  if (!scan.vertices.allFinite()) throw InputError(scan_source, "the scan has non-finite vertex coordinates");
  ScanRegistration result;
  const double volume = SignedVolume(scan);
  const bool flip = volume < 0;
  if (flip) result.warnings.push_back("the scan's faces are oriented inwards (negative volume); normals were flipped");
  const ScanSamples samples = SampleScan(scan, options.num_scan_samples, flip);
  if (samples.points.size() < 100) throw InputError(scan_source, "the scan has (almost) no surface area");
  const KdTree tree(&samples.points);
  std::vector<int> residual_samples;
  {
    const double step = static_cast<double>(samples.points.size()) / options.num_scan_residuals;
    for (double i = 0; i < samples.points.size(); i += std::max(1.0, step)) residual_samples.push_back(static_cast<int>(i));
  }
  // Principal axes of the scan surface.
  Vector3d centroid = Vector3d::Zero();
  for (const Vector3d& p : samples.points) centroid += p;
  centroid /= samples.points.size();
  Matrix3d covariance = Matrix3d::Zero();
  for (const Vector3d& p : samples.points) covariance += (p - centroid) * (p - centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Matrix3d> eigen(covariance / samples.points.size());
  const Vector3d major = eigen.eigenvectors().col(2), second = eigen.eigenvectors().col(1);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vector3d& p : samples.points) {
    lo = std::min(lo, p.dot(major));
    hi = std::max(hi, p.dot(major));
  }
  const double scan_extent = hi - lo;

  // Shape and length scale.
  const TemplatePose rest_pose;
  FitParams fp;
  bool default_shape = true;
  for (int s = 0; s < kNumBodySegments; ++s)
    default_shape = default_shape && options.initial_shape.length_scale[s] == 1.0 && options.initial_shape.girth_scale[s] == 1.0;
  BodyShape shape = options.initial_shape;
  if (options.fit_shape && default_shape && !options.initial_pose) {
    const Mesh generic = body.PosedMesh(BodyShape(), rest_pose);
    const double generic_height = generic.vertices.col(2).maxCoeff() - generic.vertices.col(2).minCoeff();
    shape = BodyShape::Uniform(1.75 * scan_extent / generic_height);
    shape.depth_scale = options.initial_shape.depth_scale;
    shape.taper_scale = options.initial_shape.taper_scale;
    shape.depth_offset = options.initial_shape.depth_offset;
    shape.mid_bulge = options.initial_shape.mid_bulge;
  }
  ShapeToParams(shape, fp.shape, nullptr, fp.section);  // the cross-sections stay as given
  double scale = 0;  // scan units per template metre
  for (int s = 0; s < kNumBodySegments; ++s) scale += shape.length_scale[s] / kNumBodySegments;
  const double min_cos = std::cos(options.max_normal_angle_deg * M_PI / 180.0);
  const double loss = options.loss_scale_m * scale;

  const int candidates = static_cast<int>(residual_samples.size() + kNumBodySegments * body.mesh_coords().size());
  // Arm hypotheses from a placed body: A-pose (the template's rest), T-pose, arms down.
  auto best_arms = [&](const FitParams& base) {
    double best_score = std::numeric_limits<double>::infinity();
    FitParams best = base;
    for (double arm_deg : {40.0, 90.0, 12.0}) {
      FitParams h = base;
      h.dofs[kJointLeftShoulder] = ArmAngle(body, kJointLeftShoulder, arm_deg);
      h.dofs[kJointRightShoulder] = ArmAngle(body, kJointRightShoulder, arm_deg);
      const double max_d = options.max_pair_distance_m * scale;
      for (int round = 0; round < 2; ++round) {
        Pairing pairing = MakePairs(body, h, samples, tree, residual_samples, max_d, min_cos, loss);
        Solve(body, &pairing, options, false, false, scale, h, &h);
      }
      const Pairing check = MakePairs(body, h, samples, tree, residual_samples, max_d, min_cos, loss);
      const double score = HypothesisScore(check, candidates, max_d);
      if (score < best_score) {
        best_score = score;
        best = h;
      }
    }
    return best;
  };
  // The full fit: every joint (and the shape), shrinking pairing distance. The joint prior pulls
  // towards the initial pose when one is given, else towards the template's rest pose.
  auto full_fit = [&](FitParams fit) {
    FitParams prior = fit;
    prior.dofs = options.initial_pose ? options.initial_pose->dofs : TemplatePose().dofs;
    ShapeToParams(shape, prior.shape);
    for (int round = 0; round < options.rounds; ++round) {
      const double max_d = std::max(options.min_pair_distance_m, options.max_pair_distance_m * std::pow(0.6, round)) * scale;
      Pairing pairing = MakePairs(body, fit, samples, tree, residual_samples, max_d, min_cos, loss);
      Solve(body, &pairing, options, false, options.fit_shape, scale, prior, &fit);
    }
    return fit;
  };
  auto final_rms = [&](const FitParams& fit) {
    return MakePairs(body, fit, samples, tree, residual_samples, std::numeric_limits<double>::infinity(), min_cos, loss).rms;
  };

  if (options.initial_pose) {
    PoseToParams(*options.initial_pose, &fp);
    fp = full_fit(fp);
  } else {
    // Orientation hypotheses: up = +-major axis, lateral = +-second axis; a short rigid fit each.
    const auto rest = body.RestPositions(shape);
    const Vector3d template_centroid = AreaCentroid(body.PosedMesh(shape, rest_pose));
    double best_score = std::numeric_limits<double>::infinity();
    FitParams facing[2][2];  // [up sign][lateral sign]
    int best_up = 0, best_lateral = 0;
    for (int u = 0; u < 2; ++u)
      for (int l = 0; l < 2; ++l) {
        const Vector3d up = (u == 0 ? 1 : -1) * major;
        const Vector3d side = (l == 0 ? 1 : -1) * second;
        const Vector3d lateral = (side - up * up.dot(side)).normalized();
        Matrix3d R;
        R.col(0) = lateral;
        R.col(1) = up.cross(lateral);
        R.col(2) = up;
        FitParams h = fp;
        h.root_reference = R;
        const Vector3d t = centroid - rest[0] - R * (template_centroid - rest[0]);
        for (int k = 0; k < 3; ++k) h.root_t[k] = t[k];
        const double max_d = 2.0 * options.max_pair_distance_m * scale;
        for (int round = 0; round < 3; ++round) {
          Pairing pairing = MakePairs(body, h, samples, tree, residual_samples, max_d, min_cos, loss);
          Solve(body, &pairing, options, /*rigid=*/true, false, scale, h, &h);
        }
        const Pairing check = MakePairs(body, h, samples, tree, residual_samples, max_d, min_cos, loss);
        const double score = HypothesisScore(check, candidates, max_d);
        facing[u][l] = h;
        if (score < best_score) {
          best_score = score;
          best_up = u;
          best_lateral = l;
        }
      }
    // Front and back of a body are alike to a rigid fit of the whole (both sides of the torso are
    // convex); the feet, the face and the bent joints tell them apart once every joint is free.
    // So the best placement and the one facing the other way are both fitted in full, and the
    // smaller final residual decides: the whole rms, since the parts that tell them apart are a
    // small share of the surface, the share a trimmed rms leaves out.
    fp = full_fit(best_arms(facing[best_up][best_lateral]));
    const FitParams turned = full_fit(best_arms(facing[best_up][1 - best_lateral]));
    if (final_rms(turned) < final_rms(fp)) fp = turned;
  }

  result.shape = ParamsToShape(fp.shape, nullptr, fp.section);
  result.pose = ParamsToPose(fp);
  result.scan_height = scan_extent;
  result.metres_per_unit = GuessMetresPerUnit(scan_extent);
  {
    // The body's up direction: from the middle of the ankles to the head.
    const auto joints = body.JointPositions(result.shape, result.pose);
    result.up_in_scan = (joints[kJointHead] - 0.5 * (joints[kJointLeftAnkle] + joints[kJointRightAnkle])).normalized();
  }
  // Final statistics: every template point and scan sample paired with its nearest.
  const Pairing final_pairs =
      MakePairs(body, fp, samples, tree, residual_samples, std::numeric_limits<double>::infinity(), min_cos, loss);
  result.rms_residual_m = final_pairs.rms;
  result.trimmed_rms_residual_m = final_pairs.trimmed_rms;
  for (int s = 0; s < kNumBodySegments; ++s) result.segment_rms_m.push_back(Rms(final_pairs.segment_distances[s], 1.0));
  const Mesh posed = body.PosedMesh(result.shape, result.pose);
  const Eigen::VectorXd along_up = posed.vertices * result.up_in_scan;
  const double height = along_up.maxCoeff() - along_up.minCoeff();
  if (!(result.trimmed_rms_residual_m <= options.max_residual_fraction * height))
    throw InputError(scan_source, Fmt("the scan does not look like a human body: the template fit residual is %.3g "
                                      "(trimmed rms, scan units), more than %.3g%% of the body height %.3g",
                                      result.trimmed_rms_residual_m, 100 * options.max_residual_fraction, height));
  // Orientation report.
  const double tilt_deg = std::acos(std::clamp(result.up_in_scan.z(), -1.0, 1.0)) * 180.0 / M_PI;
  if (tilt_deg > 30.0) {
    const std::string how = tilt_deg > 135 ? "upside down" : "lying on its side";
    const std::string text = Fmt("the scan is not upright in a Z-up world (its up axis is (%.2f, %.2f, %.2f)", result.up_in_scan.x(),
                                 result.up_in_scan.y(), result.up_in_scan.z()) +
                             Fmt(", %.0f degrees from +z: ", tilt_deg) + how +
                             "); the template was posed to match it in the scan's frame";
    if (!options.allow_reorientation) throw InputError(scan_source, text);
    result.warnings.push_back(text);
  }
  if (result.metres_per_unit != 1.0)
    result.warnings.push_back(Fmt("the scan is %.3g units tall: its unit looks like %.3g m; the template was scaled to it",
                                  scan_extent, result.metres_per_unit));
  // Reference-pose check per segment: the segment's axis against the principal axis of the scan
  // surface paired with it (limbs), and its residual against the body's.
  const auto segments = SegmentsInWorld(body, fp);
  for (int s = 0; s < kNumBodySegments; ++s) {
    const bool limb = s >= int(BodySegment::kLeftUpperArm) && s != int(BodySegment::kLeftHand) &&
                      s != int(BodySegment::kRightHand) && s != int(BodySegment::kLeftFoot) &&
                      s != int(BodySegment::kRightFoot);
    const auto& points = final_pairs.scan_points[s];
    if (limb && points.size() >= 30) {
      Vector3d mean = Vector3d::Zero();
      for (const Vector3d& p : points) mean += p;
      mean /= points.size();
      Matrix3d c = Matrix3d::Zero();
      for (const Vector3d& p : points) c += (p - mean) * (p - mean).transpose();
      Eigen::SelfAdjointEigenSolver<Matrix3d> e(c);
      const Eigen::Vector3d values = e.eigenvalues();
      if (values(2) > 2.0 * values(1)) {  // elongated enough to have an axis
        const double angle = std::acos(std::min(1.0, std::abs(e.eigenvectors().col(2).dot(segments[s].axis)))) * 180.0 / M_PI;
        if (angle > options.reference_pose_tolerance_deg)
          result.warnings.push_back("reference pose: segment " + BodySegmentName(s) +
                                    Fmt(" is %.0f degrees off the scan's limb axis", angle));
      }
    }
    const double limit = std::max(3.0 * result.trimmed_rms_residual_m, 0.03 * scale);
    if (result.segment_rms_m[s] > limit)
      result.warnings.push_back("reference pose: segment " + BodySegmentName(s) +
                                Fmt(" fits poorly (rms %.3g scan units, body %.3g)", result.segment_rms_m[s],
                                    result.trimmed_rms_residual_m));
  }
  return result;
}

std::vector<double> SegmentRotationDifferencesDeg(const BodyTemplate& body, const BodyShape& shape, const TemplatePose& a,
                                                  const TemplatePose& b) {
  const Skeleton skeleton = body.MakeSkeleton(shape);
  const auto wa = WorldFromJoint(skeleton, body.ToPose(a));
  const auto wb = WorldFromJoint(skeleton, body.ToPose(b));
  std::vector<double> out;
  for (int s = 0; s < kNumBodySegments; ++s) {
    const int j = body.segments()[s].joint;
    const Eigen::AngleAxisd d(Matrix3d(wa[j].linear().transpose() * wb[j].linear()));
    out.push_back(std::abs(d.angle()) * 180.0 / M_PI);
  }
  return out;
}

}  // namespace confluent
