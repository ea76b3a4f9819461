// The studio capture: rig layout, and a tiny synthesized capture whose masks, meshes, joints and
// images agree with each other.

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "calib/easymocap_io.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "studio/actor.h"
#include "studio/presets.h"
#include "studio/synth.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(StudioRig, RingAndHeldOutCamerasLookAtTheTarget) {
  const Rig rig = MakeStudioRig();
  ASSERT_EQ(rig.size(), 10);
  EXPECT_NO_THROW(rig.Check());
  EXPECT_EQ(rig.cameras[0].name, "cam00");
  EXPECT_EQ(rig.cameras[8].name, "holdout0");
  EXPECT_EQ(rig.cameras[9].name, "holdout1");
  for (const Camera& camera : rig.cameras) {
    EXPECT_EQ(camera.width, 1024);
    EXPECT_EQ(camera.height, 768);
    const Eigen::Vector2d pixel = camera.Project(Eigen::Vector3d(0, 0, 1));
    EXPECT_NEAR(pixel.x(), 511.5, 15.0);
    EXPECT_NEAR(pixel.y(), 383.5, 15.0);
    // Whole actor in view: feet and a raised hand at 2.2 m.
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.3, 0.3, 0.0), Eigen::Vector3d(0, 0, 2.2)}) {
      const Eigen::Vector2d q = camera.Project(p);
      EXPECT_TRUE(q.x() > 0 && q.y() > 0 && q.x() < 1023 && q.y() < 767) << camera.name;
    }
    const double radius = camera.center_in_world().head<2>().norm();
    EXPECT_GT(radius, 3.0);
  }
  // Held-out cameras are at other heights than the ring.
  EXPECT_LT(rig.cameras[8].center_in_world().z(), 1.2);
  EXPECT_GT(rig.cameras[9].center_in_world().z(), 2.4);
}

// The tiny preset, cut down further: 4 + 1 cameras, 4 frames.
StudioSynthOptions TinyOptions(const std::string& dir) {
  StudioSynthOptions options = StudioSynthPreset("tiny");
  options.capture_dir = dir + "/capture";
  options.rig.num_heldout_cameras = 1;
  options.motion.num_frames = 4;
  options.motion.fps = 1.0;
  options.scene.floor_texture_px = 256;
  return options;
}

TEST(StudioSynth, TinyCaptureIsConsistentWithItsGroundTruth) {
  testing::TempDir dir;
  const StudioSynthOptions options = TinyOptions(dir.path());
  const StudioSynthSummary summary = SynthesizeCapture(options);
  EXPECT_EQ(summary.ground_truth_dir, dir.path() + "/capture_gt");
  ASSERT_EQ(summary.num_frames, 4);
  ASSERT_EQ(summary.num_cameras, 5);
  const std::string gt = summary.ground_truth_dir;
  const Rig rig = ReadEasyMocap(options.capture_dir + "/intri.yml", options.capture_dir + "/extri.yml");
  ASSERT_EQ(rig.size(), 5);
  const Mesh scan = ReadMesh(gt + "/scan.ply");
  EXPECT_TRUE(scan.has_colors());

  // Joints: forward kinematics of the documented skeleton and performance.
  const Skeleton skeleton = MakeStudioSkeleton(options.actor);
  const std::vector<Pose> poses = DefaultPerformance(skeleton, options.motion);
  const auto joints = nlohmann::json::parse(ReadTextFile(gt + "/joints.json"));
  ASSERT_EQ(joints["frames"].size(), 4u);
  ASSERT_EQ(joints["joint_names"].size(), static_cast<std::size_t>(skeleton.size()));
  for (int f = 0; f < 4; ++f) {
    const auto expected = JointPositions(skeleton, poses[f]);
    for (int j = 0; j < skeleton.size(); ++j)
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(joints["frames"][f]["positions"][j][c].get<double>(), expected[j](c), 1e-5);
  }

  for (int f = 0; f < 4; ++f) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d", f);
    const Mesh mesh = ReadMesh(gt + "/meshes/" + name + ".ply");
    ASSERT_EQ(mesh.num_vertices(), scan.num_vertices());
    ASSERT_EQ(mesh.num_faces(), scan.num_faces());
    for (const Camera& camera : rig.cameras) {
      const Image mask = ReadImage(gt + "/masks/" + camera.name + "/" + name + ".png");
      const Image image = ReadImage(options.capture_dir + "/images/" + camera.name + "/" + name + ".png");
      const Image plate = ReadImage(options.capture_dir + "/background/" + camera.name + ".png");
      ASSERT_EQ(mask.width, 160);
      ASSERT_EQ(mask.channels, 1);
      ASSERT_EQ(image.channels, 3);
      // Every vertex projects into (or within a pixel of) the mask, and every mask pixel has a
      // projected vertex within 2 pixels.
      std::vector<int> near_vertex(160 * 120, 0);
      int inside = 0;
      for (int v = 0; v < mesh.num_vertices(); ++v) {
        const Eigen::Vector2d q = camera.Project(mesh.vertices.row(v).transpose());
        const int x = static_cast<int>(std::lround(q.x())), y = static_cast<int>(std::lround(q.y()));
        bool hit = false;
        for (int dy = -2; dy <= 2; ++dy)
          for (int dx = -2; dx <= 2; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= 160 || yy >= 120) continue;
            near_vertex[yy * 160 + xx] = 1;
            if (std::abs(dx) <= 1 && std::abs(dy) <= 1) hit |= mask.at<std::uint8_t>(xx, yy) == 255;
          }
        inside += hit;
      }
      EXPECT_GT(inside, 0.995 * mesh.num_vertices()) << camera.name << " frame " << f;
      int mask_pixels = 0, explained = 0;
      double actor_difference = 0.0;
      for (int y = 0; y < 120; ++y)
        for (int x = 0; x < 160; ++x) {
          if (mask.at<std::uint8_t>(x, y) != 255) continue;
          ++mask_pixels;
          explained += near_vertex[y * 160 + x];
          for (int c = 0; c < 3; ++c)
            actor_difference += std::abs(image.at<std::uint8_t>(x, y, c) - plate.at<std::uint8_t>(x, y, c));
        }
      EXPECT_GT(mask_pixels, 300) << camera.name;
      EXPECT_GE(explained, 0.99 * mask_pixels) << camera.name << " frame " << f;
      // The actor really is in the image where the mask says.
      EXPECT_GT(actor_difference / (3.0 * mask_pixels), 15.0) << camera.name;
    }
  }
  // Far from the actor the image is the clean plate up to sensor noise.
  const Image image = ReadImage(options.capture_dir + "/images/cam00/000000.png");
  const Image plate = ReadImage(options.capture_dir + "/background/cam00.png");
  double difference = 0.0;
  for (int x = 0; x < 20; ++x) difference += std::abs(image.at<std::uint8_t>(x, 5, 1) - plate.at<std::uint8_t>(x, 5, 1));
  EXPECT_LT(difference / 20.0, 6.0);
}

// --scan-frame: the scan is the actor as posed at that frame (its ground-truth mesh, with the
// rest mesh's colours); a frame beyond the performance is refused.
TEST(StudioSynth, ScanFrameIsTheActorAsPosedAtThatFrame) {
  testing::TempDir dir;
  StudioSynthOptions options = TinyOptions(dir.path());
  options.scan_frame = 2;
  const StudioSynthSummary summary = SynthesizeCapture(options);
  const Mesh scan = ReadMesh(options.capture_dir + "/scan.ply");
  const Mesh posed = ReadMesh(summary.ground_truth_dir + "/meshes/000002.ply");
  const Mesh rest = BuildStudioActor(options.actor).mesh;
  ASSERT_EQ(scan.num_vertices(), posed.num_vertices());
  EXPECT_LT((scan.vertices - posed.vertices).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_GT((scan.vertices - rest.vertices).rowwise().norm().maxCoeff(), 0.05);  // the pose differs from rest
  EXPECT_TRUE(scan.has_colors());
  options.scan_frame = summary.num_frames;
  EXPECT_THROW(SynthesizeCapture(options), UsageError);
}

TEST(StudioSynth, BadOptionsThrowUsageError) {
  StudioSynthOptions options;
  EXPECT_THROW(SynthesizeCapture(options), UsageError);  // no --out
  options.capture_dir = "/tmp/unused";
  options.rig.width_px = 0;
  EXPECT_THROW(SynthesizeCapture(options), UsageError);
  options = StudioSynthOptions();
  options.capture_dir = "/tmp/unused";
  options.actor_sequence_dir = "/nonexistent/sequence";
  EXPECT_THROW(SynthesizeCapture(options), InputError);
}

}  // namespace
}  // namespace confluent
