// Confluent Motion: exactness, elbow transfer, marker placement (report Fig. 4), singularities,
// and bad input.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <complex>
#include <fstream>
#include <random>

#include "core/error.h"
#include "core/mesh_ops.h"
#include "deform/confluent_motion.h"
#include "tests/deform/test_geometry.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using testing::AngleDeg;
using testing::SliceCentre;

// A sphere with bumps (not symmetric), so a wrong rotation cannot hide.
Mesh BumpySphere() {
  Mesh mesh = SubdivideMidpoint(MakeUvSphere(0.3, 12, 16));
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3d p = mesh.vertices.row(v);
    mesh.vertices.row(v) *= 1.0 + 0.2 * std::sin(3 * p.x() / 0.3) * std::cos(2 * p.y() / 0.3) + 0.1 * p.z() / 0.3;
  }
  return mesh;
}

Correspondences RandomPairs(int count, int num_faces, unsigned seed, int num_scan_faces = -1) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> face(0, num_faces - 1);
  Correspondences c;
  std::set<int> used;
  while (static_cast<int>(c.pairs.size()) < count) {
    const int f = face(rng);
    if (!used.insert(f).second) continue;
    c.pairs.push_back({f, num_scan_faces < 0 ? f : f % num_scan_faces, "", 1.0});
  }
  return c;
}

TEST(ConfluentMotion, RigidMotionOfIdenticalMeshIsReproduced) {
  const Mesh mesh = BumpySphere();
  const Correspondences pairs = RandomPairs(12, mesh.num_faces(), 5);
  ConfluentMotion motion(mesh, mesh, pairs);
  EXPECT_TRUE(motion.setup_summary().warnings.empty());
  const double size = (mesh.vertices.colwise().maxCoeff() - mesh.vertices.colwise().minCoeff()).norm();
  for (int frame = 0; frame < 3; ++frame) {
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(0.9 * (frame + 1), Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
    const Eigen::RowVector3d t(0.4 * frame, -1.0, 2.5);
    const RowMatrixX3d moved = (mesh.vertices * r.transpose()).rowwise() + t;
    DeformSummary summary;
    const RowMatrixX3d result = motion.Deform(moved, &summary);
    EXPECT_LT((result - moved).cwiseAbs().maxCoeff() / size, 1e-6) << "frame " << frame;
    EXPECT_LT(summary.placement_rms_m, 1e-6 * size);
  }
}

TEST(ConfluentMotion, RigidMotionTransfersToADifferentMesh) {
  // Template: coarse bumpy sphere; scan: a finer, differently tessellated, offset capsule.
  const Mesh template_mesh = BumpySphere();
  Mesh scan = MakeCapsule(0.25, 0.3, 8, 24);
  scan.vertices.rowwise() += Eigen::RowVector3d(0.02, -0.01, 0.03);
  Correspondences pairs;
  for (int k = 0; k < 10; ++k) {
    const int s = (k * 7919) % scan.num_faces();
    pairs.pairs.push_back({testing::NearestFace(template_mesh, testing::FaceCentroid(scan, s)), s, "", 1.0});
  }
  ConfluentMotion motion(scan, template_mesh, pairs);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(2.0, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  const Eigen::RowVector3d t(1, 2, 3);
  const RowMatrixX3d result = motion.Deform((template_mesh.vertices * r.transpose()).rowwise() + t);
  const RowMatrixX3d expected = (scan.vertices * r.transpose()).rowwise() + t;
  EXPECT_LT((result - expected).cwiseAbs().maxCoeff(), 1e-6 * 0.8);
}

// Elbow angle from ring centres on both sides of the joint at z = 0.3.
double ElbowAngleDeg(const RowMatrixX3d& reference, const RowMatrixX3d& deformed) {
  const Eigen::Vector3d upper = SliceCentre(reference, deformed, 0.14, 0.16) - SliceCentre(reference, deformed, 0.04, 0.06);
  const Eigen::Vector3d lower = SliceCentre(reference, deformed, 0.54, 0.56) - SliceCentre(reference, deformed, 0.44, 0.46);
  return AngleDeg(upper, lower);
}

TEST(ConfluentMotion, BentCapsuleArmDrivesFinerArm) {
  const Mesh template_mesh = testing::MakeTube(0.04, 0.6, 24, 12);
  const Mesh scan = testing::MakeTube(0.045, 0.6, 60, 32, 0.13);
  const Correspondences pairs = testing::TubePairs(template_mesh, scan, {0.1, 0.2, 0.4, 0.5}, 4, 0.04, 0.3);
  ConfluentMotion motion(scan, template_mesh, pairs);
  EXPECT_EQ(motion.setup_summary().num_segment_fields, 2);
  for (double bend_deg : {45.0, 90.0}) {
    const Eigen::Matrix3d bend = Eigen::AngleAxisd(bend_deg * M_PI / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const RowMatrixX3d posed = testing::RotateAbove(template_mesh.vertices, 0.3, bend);
    DeformSummary summary;
    const RowMatrixX3d result = motion.Deform(posed, &summary);
    EXPECT_TRUE(summary.used_segment_fields);
    EXPECT_NEAR(ElbowAngleDeg(template_mesh.vertices, posed), bend_deg, 1e-6);
    EXPECT_NEAR(ElbowAngleDeg(scan.vertices, result), bend_deg, 2.0);
    // The wrist follows the template's wrist.
    const Eigen::Vector3d template_tip = SliceCentre(template_mesh.vertices, posed, 0.59, 0.61);
    const Eigen::Vector3d scan_tip = SliceCentre(scan.vertices, result, 0.59, 0.61);
    EXPECT_LT((template_tip - scan_tip).norm(), 0.03);
  }
}

TEST(ConfluentMotion, SegmentFieldsEqualTheGeneralSolve) {
  const Mesh template_mesh = testing::MakeTube(0.04, 0.6, 24, 12);
  const Mesh scan = testing::MakeTube(0.045, 0.6, 40, 20, 0.13);
  const Correspondences pairs = testing::TubePairs(template_mesh, scan, {0.1, 0.2, 0.4, 0.5}, 4, 0.04, 0.3);
  ConfluentMotionOptions general;
  general.segment_fields = false;
  ConfluentMotion fast(scan, template_mesh, pairs), slow(scan, template_mesh, pairs, general);
  const RowMatrixX3d posed = testing::RotateAbove(
      template_mesh.vertices, 0.3, Eigen::AngleAxisd(1.2, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix());
  DeformSummary a, b;
  const RowMatrixX3d x = fast.Deform(posed, &a), y = slow.Deform(posed, &b);
  EXPECT_TRUE(a.used_segment_fields);
  EXPECT_FALSE(b.used_segment_fields);
  EXPECT_LT((x - y).cwiseAbs().maxCoeff(), 1e-9);
  // A non-rigid template frame falls back to the general solve.
  RowMatrixX3d wobbly = posed;
  wobbly.row(template_mesh.faces(pairs.pairs[0].template_triangle, 0)) += Eigen::RowVector3d(0.01, 0, 0);
  fast.Deform(wobbly, &a);
  EXPECT_FALSE(a.used_segment_fields);
}

// A scan large enough for the two-thread loops and solves (and with a face count that is not a
// multiple of the assembly's block): two threads and single-precision factors give the serial
// double-precision result, frame after frame.
TEST(ConfluentMotion, ThreadsAndSinglePrecisionAgreeWithSerialDouble) {
  const Mesh template_mesh = testing::MakeTube(0.04, 0.6, 24, 12);
  const Mesh scan = testing::MakeTube(0.045, 0.6, 200, 45, 0.13);
  ASSERT_GE(scan.num_faces(), 16384);
  ASSERT_NE(scan.num_faces() % 8, 0);
  const Correspondences pairs = testing::TubePairs(template_mesh, scan, {0.1, 0.2, 0.4, 0.5}, 4, 0.04, 0.3);
  ConfluentMotionOptions serial_double, two_single;
  serial_double.threads = 1;
  two_single.single_precision_solves = true;
  ConfluentMotion reference(scan, template_mesh, pairs, serial_double), two(scan, template_mesh, pairs),
      fast(scan, template_mesh, pairs, two_single);
  for (int frame = 0; frame < 3; ++frame) {
    RowMatrixX3d posed = testing::RotateAbove(
        template_mesh.vertices, 0.3,
        Eigen::AngleAxisd(0.4 * (frame + 1), Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix());
    if (frame == 2)  // not segment-rigid: the harmonic solve per frame
      posed.row(template_mesh.faces(pairs.pairs[0].template_triangle, 0)) += Eigen::RowVector3d(0.002, 0, 0);
    DeformSummary a, b, c;
    const RowMatrixX3d x = reference.Deform(posed, &a), y = two.Deform(posed, &b), z = fast.Deform(posed, &c);
    EXPECT_EQ(a.used_segment_fields, frame < 2);
    EXPECT_EQ(c.used_segment_fields, frame < 2);
    EXPECT_LT((x - y).cwiseAbs().maxCoeff(), 1e-12) << "frame " << frame;
    EXPECT_LT((x - z).cwiseAbs().maxCoeff(), 1e-5) << "frame " << frame;
    EXPECT_LT((reference.face_rotations() - fast.face_rotations()).cwiseAbs().maxCoeff(), 1e-5) << "frame " << frame;
  }
}

TEST(ConfluentMotion, MarkersNearTheJointBendSharper) {
  // Report Fig. 4: the bend is concentrated near the joint when the markers are close to it.
  const Mesh template_mesh = testing::MakeTube(0.04, 0.6, 24, 12);
  const Mesh scan = testing::MakeTube(0.045, 0.6, 60, 32, 0.13);
  const RowMatrixX3d posed = testing::RotateAbove(
      template_mesh.vertices, 0.3, Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix());
  auto local_bend = [&](const std::vector<double>& heights) {
    ConfluentMotion motion(scan, template_mesh, testing::TubePairs(template_mesh, scan, heights, 4, 0.04, 0.3));
    const RowMatrixX3d x = motion.Deform(posed);
    // Angle between the axis just below and just above the joint (+-2..5 cm).
    const Eigen::Vector3d below = SliceCentre(scan.vertices, x, 0.25, 0.25) - SliceCentre(scan.vertices, x, 0.22, 0.22);
    const Eigen::Vector3d above = SliceCentre(scan.vertices, x, 0.38, 0.38) - SliceCentre(scan.vertices, x, 0.35, 0.35);
    return AngleDeg(below, above);
  };
  const double near = local_bend({0.22, 0.25, 0.35, 0.38});
  const double far = local_bend({0.05, 0.1, 0.5, 0.55});
  EXPECT_GT(near, 75.0);
  EXPECT_LT(far, 60.0);
  EXPECT_GT(near - far, 20.0);
}

// Mean twist (radians, wrapped to (-pi, pi]) of the ring at reference height z about the z axis.
double RingTwist(const RowMatrixX3d& reference, const RowMatrixX3d& deformed, double z) {
  const Eigen::Vector3d centre = SliceCentre(reference, deformed, z - 0.001, z + 0.001);
  std::complex<double> sum = 0.0;
  for (int v = 0; v < reference.rows(); ++v)
    if (std::abs(reference(v, 2) - z) <= 0.001 && reference.row(v).head<2>().norm() > 1e-9) {
      const double before = std::atan2(reference(v, 1), reference(v, 0));
      const double after = std::atan2(deformed(v, 1) - centre.y(), deformed(v, 0) - centre.x());
      sum += std::polar(1.0, after - before);
    }
  return std::arg(sum);
}

// Report section 4.3: a forearm twisted about its own axis from 0 to 270 degrees in 10-degree
// frames. The harmonic twist between the elbow markers (z = 0.1) and the wrist markers
// (z = 0.5) should grow linearly along the arm. Without handling, the twist flips direction
// when it crosses 180 degrees (hemisphere signs) or concentrates in the middle of the arm
// (blend of nearly opposite quaternions); the intermediate reference and the SLERP paths keep
// it linear.
TEST(ConfluentMotion, CandyWrapperIsHandledByIntermediateReferenceAndSlerpPaths) {
  const Mesh template_mesh = testing::MakeTube(0.04, 0.6, 24, 12);
  const Mesh scan = testing::MakeTube(0.04, 0.6, 60, 24, 0.13);
  const Correspondences pairs = testing::TubePairs(template_mesh, scan, {0.05, 0.1, 0.5, 0.55}, 4, 0.04, 0.3);
  ConfluentMotionOptions hemisphere, temporal, intermediate, slerp;
  hemisphere.intermediate_reference = false;
  hemisphere.temporal_signs = false;
  temporal.intermediate_reference = false;
  slerp.slerp_paths = true;
  const ConfluentMotionOptions modes[] = {hemisphere, temporal, intermediate, slerp};
  std::vector<ConfluentMotion> motions;
  for (const auto& options : modes) motions.emplace_back(scan, template_mesh, pairs, options);
  double worst[4] = {0, 0, 0, 0};
  int intermediate_frames = 0, slerp_frames = 0;
  for (int frame = 0; frame <= 27; ++frame) {
    const double twist = frame * 10.0 * M_PI / 180;
    const RowMatrixX3d posed = testing::RotateAbove(
        template_mesh.vertices, 0.3, Eigen::AngleAxisd(twist, Eigen::Vector3d::UnitZ()).toRotationMatrix());
    for (int mode = 0; mode < 4; ++mode) {
      DeformSummary summary;
      const RowMatrixX3d x = motions[mode].Deform(posed, &summary);
      ASSERT_TRUE(x.allFinite());
      if (frame == 18) {  // 180 degrees: detected, handled
        EXPECT_TRUE(summary.singular);
        EXPECT_LT(summary.min_abs_w, 0.05);
      }
      if (mode == 2 && summary.reference_frame >= 0) ++intermediate_frames;
      if (mode == 3) {
        EXPECT_EQ(summary.reference_frame, -1);
        EXPECT_EQ(summary.slerp_path_vertices > 0, summary.singular) << "frame " << frame;
        slerp_frames += summary.slerp_path_vertices > 0;
      }
      for (double z : {0.2, 0.3, 0.4}) {
        const double expected = twist * (z - 0.1) / 0.4;
        const double error = std::abs(std::remainder(RingTwist(scan.vertices, x, z) - expected, 2 * M_PI));
        worst[mode] = std::max(worst[mode], error * 180 / M_PI);
      }
    }
  }
  std::printf("twist 0..270 deg, worst ring twist error: hemisphere signs %.1f deg, temporal signs %.1f deg, "
              "intermediate reference %.1f deg (%d frames), SLERP paths %.1f deg (%d frames)\n",
              worst[0], worst[1], worst[2], intermediate_frames, worst[3], slerp_frames);
  EXPECT_GT(intermediate_frames, 0);
  EXPECT_GT(slerp_frames, 0);
  EXPECT_GT(worst[0], 90.0);
  EXPECT_GT(worst[1], 20.0);
  EXPECT_LT(worst[2], 10.0);
  EXPECT_LT(worst[3], 10.0);
}

TEST(ConfluentMotion, OutOfRangeIndicesNameTheFile) {
  testing::TempDir dir;
  const Mesh template_mesh = testing::MakeTube(0.04, 0.6, 8, 8);
  const Mesh scan = testing::MakeTube(0.04, 0.6, 10, 10);
  std::ofstream(dir / "c.json") << "{\"pairs\": [{\"template_triangle\": 1, \"scan_triangle\": 2},"
                                   " {\"template_triangle\": 3, \"scan_triangle\": 99999}]}";
  const Correspondences pairs = ReadCorrespondences(dir / "c.json");
  try {
    ConfluentMotion motion(scan, template_mesh, pairs, {}, "scan.ply", dir / "c.json");
    FAIL();
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(dir / "c.json"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("99999"), std::string::npos) << error.what();
  }
}

TEST(ConfluentMotion, ComponentWithoutCorrespondenceIsNamed) {
  const Mesh template_mesh = testing::MakeTube(0.04, 0.6, 8, 8);
  Mesh scan = testing::MakeTube(0.04, 0.6, 10, 10);
  const Mesh ball = MakeUvSphere(0.05, 6, 8);
  const int n = scan.num_vertices(), m = scan.num_faces();
  scan.vertices.conservativeResize(n + ball.num_vertices(), 3);
  scan.vertices.bottomRows(ball.num_vertices()) = ball.vertices.rowwise() + Eigen::RowVector3d(0.3, 0, 0);
  scan.faces.conservativeResize(m + ball.num_faces(), 3);
  scan.faces.bottomRows(ball.num_faces()) = ball.faces.array() + n;
  Correspondences pairs;
  pairs.pairs.push_back({3, 5, "", 1.0});
  try {
    ConfluentMotion motion(scan, template_mesh, pairs, {}, "scan.ply", "c.json");
    FAIL();
  } catch (const InputError& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("scan.ply"), std::string::npos) << what;
    EXPECT_NE(what.find("component 1"), std::string::npos) << what;
    EXPECT_NE(what.find("first face " + std::to_string(m)), std::string::npos) << what;
  }
  // With a pair on the ball too, both components move.
  pairs.pairs.push_back({7, m + 3, "", 1.0});
  ConfluentMotion motion(scan, template_mesh, pairs);
  const RowMatrixX3d moved = template_mesh.vertices.rowwise() + Eigen::RowVector3d(0, 0, 1);
  const RowMatrixX3d result = motion.Deform(moved);
  EXPECT_LT((result - (scan.vertices.rowwise() + Eigen::RowVector3d(0, 0, 1))).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(ConfluentMotion, DegenerateAndNonManifoldScanGivesWarningsNotNaN) {
  const Mesh template_mesh = testing::MakeTube(0.04, 0.6, 24, 12);
  Mesh scan = testing::MakeTube(0.045, 0.6, 40, 20);
  // Zero-area faces: collapse a vertex onto its neighbour; add a repeated-index face, a fin
  // (non-manifold edge) and an unreferenced vertex.
  scan.vertices.row(20 * 20 + 3) = scan.vertices.row(20 * 20 + 4);
  const int m = scan.num_faces();
  scan.faces.conservativeResize(m + 2, 3);
  scan.faces.row(m) << 10, 10, 11;
  scan.vertices.conservativeResize(scan.num_vertices() + 2, 3);
  scan.vertices.row(scan.num_vertices() - 2) << 0.2, 0.0, 0.3;
  scan.vertices.row(scan.num_vertices() - 1) << 9.0, 9.0, 9.0;
  scan.faces.row(m + 1) << scan.faces(100, 0), scan.faces(100, 1), scan.num_vertices() - 2;
  const Correspondences pairs = testing::TubePairs(template_mesh, scan, {0.1, 0.2, 0.4, 0.5}, 4, 0.04, 0.3);
  ConfluentMotion motion(scan, template_mesh, pairs);
  const auto& warnings = motion.setup_summary().warnings;
  auto has = [&](const std::string& needle) {
    for (const auto& w : warnings)
      if (w.find(needle) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("zero area")) << ::testing::PrintToString(warnings);
  EXPECT_TRUE(has("non-manifold")) << ::testing::PrintToString(warnings);
  EXPECT_TRUE(has("belong to no face")) << ::testing::PrintToString(warnings);
  const RowMatrixX3d posed = testing::RotateAbove(
      template_mesh.vertices, 0.3, Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix());
  const RowMatrixX3d result = motion.Deform(posed);
  ASSERT_TRUE(result.allFinite());
  EXPECT_NEAR(ElbowAngleDeg(scan.vertices, result), 90.0, 3.0);
}

TEST(ConfluentMotion, ZeroAreaTemplateTriangleIsRejected) {
  Mesh template_mesh = testing::MakeTube(0.04, 0.6, 8, 8);
  const Mesh scan = testing::MakeTube(0.04, 0.6, 10, 10);
  template_mesh.vertices.row(template_mesh.faces(5, 1)) = template_mesh.vertices.row(template_mesh.faces(5, 0));
  Correspondences pairs;
  pairs.pairs.push_back({5, 5, "", 1.0});
  EXPECT_THROW(ConfluentMotion(scan, template_mesh, pairs, {}, "s", "c.json"), InputError);
}

}  // namespace
}  // namespace confluent
