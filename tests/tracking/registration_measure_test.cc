// Issue 7 "done when" measurements (slow; skipped unless CONFLUENT_MEASURE_REGISTRATION=1):
//  - the studio's default actor: registration from its rest pose, the template driven by the
//    ground-truth skeleton, the scan animated with Confluent Motion, mean vertex error against
//    the ground-truth meshes (folder $CONFLUENT_STUDIO_GT, default /tmp/studio_default_gt);
//  - samba (shared data): the template registered to frame 0, driven by a warm-started fit to
//    every ground-truth frame; automatic correspondences against correspondences from the
//    augmentation rule (one seed per segment, AugmentCorrespondences), same driving.
// CONFLUENT_MEASURE_STRIDE (default 5) picks every n-th frame.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <nlohmann/json.hpp>

#include "core/mesh_io.h"
#include "core/mesh_ops.h"
#include "deform/confluent_motion.h"
#include "deform/correspondence_placement.h"
#include "tests/support/test_support.h"
#include "tracking/pose_from_joints.h"
#include "tracking/scan_registration.h"

namespace confluent {
namespace {

using Eigen::Vector3d;

bool Enabled() {
  const char* e = std::getenv("CONFLUENT_MEASURE_REGISTRATION");
  return e && std::string(e) == "1";
}

int Stride() {
  const char* s = std::getenv("CONFLUENT_MEASURE_STRIDE");
  return s ? std::max(1, std::atoi(s)) : 5;
}

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void PrintCounts(const Correspondences& pairs) {
  std::map<std::string, int> counts;
  for (const auto& p : pairs.pairs) ++counts[p.segment];
  std::printf("  %zu pairs:", pairs.pairs.size());
  for (const auto& [name, n] : counts) std::printf(" %s=%d", name.c_str(), n);
  std::printf("\n");
}

TEST(RegistrationMeasure, StudioDefaultActorDrivenByGroundTruthSkeleton) {
  if (!Enabled()) GTEST_SKIP() << "set CONFLUENT_MEASURE_REGISTRATION=1 to measure";
  const char* gt_env = std::getenv("CONFLUENT_STUDIO_GT");
  const std::string gt = gt_env ? gt_env : "/tmp/studio_default_gt";
  if (!std::filesystem::exists(gt + "/joints.json")) GTEST_SKIP() << "no studio ground truth in " << gt;
  const Mesh scan = ReadMesh(gt + "/scan.ply");
  const BodyTemplate body;
  auto start = std::chrono::steady_clock::now();
  const ScanRegistration registration = RegisterTemplateToScan(body, scan);
  std::printf("studio: registration %.1f s, rms %.4f m, trimmed %.4f m, %zu warnings\n", Seconds(start),
              registration.rms_residual_m, registration.trimmed_rms_residual_m, registration.warnings.size());
  for (const auto& w : registration.warnings) std::printf("  warning: %s\n", w.c_str());
  const Mesh reference = body.PosedMesh(registration.shape, registration.pose);
  CorrespondencePlacementOptions placement;
  placement.joint_positions = body.JointPositions(registration.shape, registration.pose);
  start = std::chrono::steady_clock::now();
  const Correspondences pairs = PlaceCorrespondences(reference, scan, placement);
  std::printf("studio: placement %.1f s\n", Seconds(start));
  PrintCounts(pairs);
  ConfluentMotion motion(scan, reference, pairs);

  const nlohmann::json joints = nlohmann::json::parse(std::ifstream(gt + "/joints.json"));
  const std::vector<int> parents = joints["parents"].get<std::vector<int>>();
  const auto reference_world = WorldFromJoint(body.MakeSkeleton(registration.shape), body.ToPose(registration.pose));
  TemplatePose pose = registration.pose;
  double sum = 0;
  long count = 0;
  std::vector<double> frame_means;
  const int stride = Stride();
  for (std::size_t i = 0; i < joints["frames"].size(); i += stride) {
    const auto& frame = joints["frames"][i];
    std::vector<Vector3d> positions;
    for (const auto& p : frame["positions"]) positions.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
    std::vector<Eigen::Quaterniond> world(positions.size());
    for (std::size_t j = 0; j < positions.size(); ++j) {
      const auto& q = frame["local_rotations_wxyz"][j];
      const Eigen::Quaterniond local(q[0].get<double>(), q[1].get<double>(), q[2].get<double>(), q[3].get<double>());
      world[j] = parents[j] < 0 ? local : world[parents[j]] * local;
    }
    // The template's segments rotate from the registered reference as the skeleton's bones from rest.
    std::vector<Eigen::Quaterniond> targets(world.size());
    for (std::size_t j = 0; j < world.size(); ++j) targets[j] = world[j] * Eigen::Quaterniond(reference_world[j].linear());
    pose = FitPoseToJoints(body, registration.shape, positions, &targets, pose);
    const RowMatrixX3d x = motion.Deform(body.PosedMesh(registration.shape, pose).vertices);
    char name[32];
    std::snprintf(name, sizeof name, "/meshes/%06d.ply", frame["frame"].get<int>());
    const Mesh truth = ReadMesh(gt + name);
    double frame_sum = 0;
    for (int v = 0; v < x.rows(); ++v) frame_sum += (x.row(v) - truth.vertices.row(v)).norm();
    frame_means.push_back(frame_sum / x.rows());
    sum += frame_sum;
    count += x.rows();
  }
  const double mean = sum / count;
  std::printf("studio: %zu frames (every %d-th of %zu), mean vertex error %.2f cm, worst frame %.2f cm\n",
              frame_means.size(), stride, joints["frames"].size(), 100 * mean,
              100 * *std::max_element(frame_means.begin(), frame_means.end()));
  EXPECT_LE(mean, 0.015);
}

// One seed pair per segment (the template triangle nearest the middle of the segment on its
// front, paired with the nearest scan triangle), completed by the augmentation rule.
Correspondences AugmentationRulePairs(const Mesh& reference, const Mesh& scan) {
  Correspondences seeds;
  std::vector<Vector3d> scan_centroids(scan.num_faces());
  for (int f = 0; f < scan.num_faces(); ++f)
    scan_centroids[f] = (scan.vertices.row(scan.faces(f, 0)) + scan.vertices.row(scan.faces(f, 1)) +
                         scan.vertices.row(scan.faces(f, 2))).transpose() / 3.0;
  const RowMatrixX3d normals = FaceNormals(reference), scan_normals = FaceNormals(scan);
  for (int s = 0; s < kNumBodySegments; ++s) {
    Vector3d centre = Vector3d::Zero();
    int n = 0;
    for (int f = 0; f < reference.num_faces(); ++f)
      if (reference.face_labels[f] == s) {
        centre += reference.vertices.row(reference.faces(f, 0)).transpose();
        ++n;
      }
    centre /= n;
    int best = -1;
    double best_d = 1e18;
    for (int f = 0; f < reference.num_faces(); ++f) {
      if (reference.face_labels[f] != s) continue;
      const Vector3d c = reference.vertices.row(reference.faces(f, 0)).transpose();
      const double d = (c - centre).norm();
      if (d < best_d) {
        best_d = d;
        best = f;
      }
    }
    const Vector3d c = (reference.vertices.row(reference.faces(best, 0)) + reference.vertices.row(reference.faces(best, 1)) +
                        reference.vertices.row(reference.faces(best, 2))).transpose() / 3.0;
    int best_scan = -1;
    best_d = 1e18;
    for (int g = 0; g < scan.num_faces(); ++g) {
      const double d = (scan_centroids[g] - c).norm();
      if (d < best_d && normals.row(best).dot(scan_normals.row(g)) > 0.3) {
        best_d = d;
        best_scan = g;
      }
    }
    seeds.pairs.push_back({best, best_scan, BodySegmentName(s), 1.0});
  }
  return AugmentCorrespondences(reference, scan, seeds);
}

TEST(RegistrationMeasure, SambaAutomaticAgainstAugmentationRule) {
  if (!Enabled()) GTEST_SKIP() << "set CONFLUENT_MEASURE_REGISTRATION=1 to measure";
  const std::string archive = testing::SharedDataPath("meshseq/vlasic_samba.tar.xz");
  if (archive.empty()) GTEST_SKIP() << "shared data meshseq/vlasic_samba.tar.xz not available";
  testing::TempDir dir;
  const std::vector<std::string> files = testing::ExtractSambaSequence(dir.path());
  ASSERT_EQ(files.size(), 175u);
  // Every frame is fitted (warm start from the previous one) when CONFLUENT_MEASURE_DRIVE_ALL=1;
  // the error is measured on every stride-th frame.
  const int stride = Stride();
  const bool drive_all = std::getenv("CONFLUENT_MEASURE_DRIVE_ALL") != nullptr;
  std::vector<Mesh> frames, between;
  std::vector<int> frame_of_between;
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (i % stride == 0) frames.push_back(ReadMesh(files[i]));
    else if (drive_all) {
      between.push_back(ReadMesh(files[i]));
      frame_of_between.push_back(static_cast<int>(i));
    }
  }
  const Mesh scan = SubdivideMidpoint(frames[0]);
  const int n = frames[0].num_vertices();
  const BodyTemplate body;
  auto start = std::chrono::steady_clock::now();
  const ScanRegistration registration = RegisterTemplateToScan(body, frames[0]);
  std::printf("samba: registration %.1f s, rms %.4f m, trimmed %.4f m\n", Seconds(start), registration.rms_residual_m,
              registration.trimmed_rms_residual_m);
  for (const auto& w : registration.warnings) std::printf("  warning: %s\n", w.c_str());
  const Mesh reference = body.PosedMesh(registration.shape, registration.pose);
  // The template driven by a warm-started fit to every ground-truth frame (shape fixed).
  start = std::chrono::steady_clock::now();
  std::vector<RowMatrixX3d> driven;
  ScanRegistrationOptions track;
  track.fit_shape = false;
  track.initial_shape = registration.shape;
  track.rounds = 6;
  track.max_pair_distance_m = 0.12;
  track.max_residual_fraction = 1.0;  // report, do not refuse, a frame that fits badly
  TemplatePose pose = registration.pose;
  double fit_rms = 0;
  std::size_t next_between = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    for (; next_between < between.size() && frame_of_between[next_between] < static_cast<int>(i) * stride; ++next_between) {
      track.initial_pose = pose;
      pose = RegisterTemplateToScan(body, between[next_between], track, "samba frame").pose;
    }
    track.initial_pose = pose;
    const ScanRegistration fit = RegisterTemplateToScan(body, frames[i], track, "samba frame");
    pose = fit.pose;
    fit_rms += fit.trimmed_rms_residual_m / frames.size();
    if (std::getenv("CONFLUENT_MEASURE_VERBOSE"))
      std::printf("  frame %zu: trimmed rms %.4f m\n", i * stride, fit.trimmed_rms_residual_m);
    driven.push_back(body.PosedMesh(registration.shape, pose).vertices);
  }
  std::printf("samba: template fitted to %zu frames (every %d-th) in %.1f s, mean trimmed rms %.4f m\n", frames.size(),
              stride, Seconds(start), fit_rms);
  auto measure = [&](const Correspondences& pairs) {
    ConfluentMotion motion(scan, reference, pairs);
    double sum = 0;
    std::vector<double> errors;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const RowMatrixX3d x = motion.Deform(driven[i]);
      for (int v = 0; v < n; ++v) errors.push_back((x.row(v) - frames[i].vertices.row(v)).norm());
    }
    for (double e : errors) sum += e;
    std::nth_element(errors.begin(), errors.begin() + errors.size() * 95 / 100, errors.end());
    return std::make_pair(sum / errors.size(), errors[errors.size() * 95 / 100]);
  };
  CorrespondencePlacementOptions placement;
  placement.joint_positions = body.JointPositions(registration.shape, registration.pose);
  const Correspondences automatic = PlaceCorrespondences(reference, scan, placement);
  PrintCounts(automatic);
  const Correspondences augmented = AugmentationRulePairs(reference, scan);
  PrintCounts(augmented);
  const auto [auto_mean, auto_p95] = measure(automatic);
  const auto [aug_mean, aug_p95] = measure(augmented);
  std::printf("| correspondences | pairs | mean (cm) | 95th pct (cm) |\n|---|---|---|---|\n");
  std::printf("| automatic (issue 7) | %zu | %.2f | %.2f |\n", automatic.pairs.size(), 100 * auto_mean, 100 * auto_p95);
  std::printf("| augmentation rule (16 seeds) | %zu | %.2f | %.2f |\n", augmented.pairs.size(), 100 * aug_mean, 100 * aug_p95);
  std::printf("ratio automatic / augmentation rule: %.3f\n", auto_mean / aug_mean);
  EXPECT_LE(auto_mean, 1.3 * aug_mean);
}

}  // namespace
}  // namespace confluent

namespace confluent {
namespace {

TEST(RegistrationMeasure, MakeHumanSubdividedIsRegisteredWithoutManualInput) {
  if (!Enabled()) GTEST_SKIP() << "set CONFLUENT_MEASURE_REGISTRATION=1 to measure";
  const std::string path = testing::SharedDataPath("makehuman/base.obj");
  if (path.empty()) GTEST_SKIP() << "shared data makehuman/base.obj not available";
  // The body group only (the file's first group; the helper geometry - tights, skirt, hair,
  // joint cubes - follows it), then one midpoint subdivision.
  const Mesh full = ReadMesh(path);
  int body_triangles = 0;
  {
    std::ifstream in(path);
    std::string line, group;
    while (std::getline(in, line)) {
      if (line.rfind("g ", 0) == 0) group = line.substr(2);
      if (line.rfind("f ", 0) == 0) {
        if (group != "body") break;
        std::istringstream corners(line.substr(2));
        std::string corner;
        int n = 0;
        while (corners >> corner) ++n;
        body_triangles += n - 2;
      }
    }
  }
  ASSERT_GT(body_triangles, 0);
  ASSERT_LE(body_triangles, full.num_faces());
  Mesh body_only;
  {
    std::vector<int> index(full.num_vertices(), -1);
    std::vector<Eigen::Vector3d> vertices;
    body_only.faces.resize(body_triangles, 3);
    for (int f = 0; f < body_triangles; ++f)
      for (int k = 0; k < 3; ++k) {
        int& i = index[full.faces(f, k)];
        if (i < 0) {
          i = static_cast<int>(vertices.size());
          vertices.push_back(full.vertices.row(full.faces(f, k)).transpose());
        }
        body_only.faces(f, k) = i;
      }
    body_only.vertices.resize(vertices.size(), 3);
    for (std::size_t v = 0; v < vertices.size(); ++v) body_only.vertices.row(v) = vertices[v].transpose();
  }
  const Mesh scan = SubdivideMidpoint(body_only);
  std::printf("makehuman: %d vertices, %d triangles after one midpoint subdivision\n", scan.num_vertices(), scan.num_faces());
  if (const char* out = std::getenv("CONFLUENT_MEASURE_OUT")) WriteMesh(std::string(out) + "/makehuman_subdivided.ply", scan);
  const BodyTemplate body;
  auto start = std::chrono::steady_clock::now();
  const ScanRegistration registration = RegisterTemplateToScan(body, scan, {}, path);
  std::printf("makehuman: registration %.1f s, rms %.4f, trimmed %.4f (scan units, %.3g m per unit)\n", Seconds(start),
              registration.rms_residual_m, registration.trimmed_rms_residual_m, registration.metres_per_unit);
  for (const auto& w : registration.warnings) std::printf("  warning: %s\n", w.c_str());
  CorrespondencePlacementOptions placement;
  placement.metres_per_unit = registration.metres_per_unit;
  placement.joint_positions = body.JointPositions(registration.shape, registration.pose);
  const Mesh reference = body.PosedMesh(registration.shape, registration.pose);
  const Correspondences pairs = PlaceCorrespondences(reference, scan, placement);
  PrintCounts(pairs);
  EXPECT_GE(pairs.pairs.size(), 140u);
  EXPECT_LE(pairs.pairs.size(), 220u);
  EXPECT_TRUE(SegmentsWithoutPairs(pairs, [] {
                std::vector<std::string> names;
                for (int s = 0; s < kNumBodySegments; ++s) names.push_back(BodySegmentName(s));
                return names;
              }()).empty());
}

}  // namespace
}  // namespace confluent
