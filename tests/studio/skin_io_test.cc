// Rigged actors for the studio (studio/skin_io.h): skin.json round trip, and bad input.

#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "core/mesh_io.h"
#include "core/skinning.h"
#include "studio/actor.h"
#include "studio/motion.h"
#include "studio/skin_io.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

StudioActor SmallActor() {
  StudioActorOptions options;
  options.target_triangles = 6000;
  return BuildStudioActor(options);
}

void ExpectInputError(const std::string& mesh, const std::string& skin, const std::string& fragment) {
  try {
    ReadRiggedActor(mesh, skin);
    ADD_FAILURE() << "no error for " << fragment;
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(skin), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos) << error.what();
  }
}

TEST(StudioSkin, RoundTripPerformsLikeTheProceduralActor) {
  const StudioActor actor = SmallActor();
  testing::TempDir dir;
  WriteMesh(dir / "body.ply", actor.mesh);
  std::ofstream(dir / "skin.json") << StudioSkinJson(actor);
  const StudioActor rigged = ReadRiggedActor(dir / "body.ply", dir / "skin.json");
  ASSERT_EQ(rigged.skeleton.size(), actor.skeleton.size());
  for (int j = 0; j < actor.skeleton.size(); ++j) {
    EXPECT_EQ(rigged.skeleton.joints[j].name, actor.skeleton.joints[j].name);
    EXPECT_EQ(rigged.skeleton.joints[j].parent, actor.skeleton.joints[j].parent);
    EXPECT_LT((rigged.skeleton.joints[j].offset_in_parent - actor.skeleton.joints[j].offset_in_parent).norm(), 1e-8);
  }
  EXPECT_EQ(rigged.segment_joint, actor.segment_joint);
  EXPECT_EQ(rigged.weights.joints, actor.weights.joints);
  EXPECT_LT((rigged.weights.weights - actor.weights.weights).cwiseAbs().maxCoeff(), 1e-8);
  // The same performance poses both alike (PLY stores float coordinates).
  StudioMotionOptions motion;
  motion.num_frames = 60;
  const std::vector<Pose> poses = StudioPerformance(actor.skeleton, motion);
  const std::vector<Pose> rigged_poses = StudioPerformance(rigged.skeleton, motion);
  for (int frame : {20, 59}) {
    const RowMatrixX3d a = SkinVertices(actor.mesh.vertices, actor.weights, actor.skeleton, poses[frame]);
    const RowMatrixX3d b = SkinVertices(rigged.mesh.vertices, rigged.weights, rigged.skeleton, rigged_poses[frame]);
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-5) << "frame " << frame;
  }
}

TEST(StudioSkinBadInput, EachProblemNamesTheFile) {
  const StudioActor actor = SmallActor();
  testing::TempDir dir;
  const std::string mesh = dir / "body.ply";
  WriteMesh(mesh, actor.mesh);
  const std::string good = StudioSkinJson(actor);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return std::string(dir / name);
  };
  ExpectInputError(mesh, write("truncated.json", good.substr(0, good.size() / 2)), "not valid JSON");
  std::string renamed = good;
  renamed.replace(renamed.find("\"left_elbow\""), 12, "\"left_ellbow\"");
  ExpectInputError(mesh, write("renamed.json", renamed), "left_elbow");
  // One weights row fewer than vertices.
  std::string short_rows = good;
  const std::size_t last_row = short_rows.rfind(",\n    [");
  short_rows.erase(last_row, short_rows.rfind("]\n  ]") + 1 - last_row);
  ExpectInputError(mesh, write("short.json", short_rows), "rows but the mesh has");
  std::string bad_sum = good;
  const std::size_t first_row = bad_sum.find("\"weights\": [\n    [") + 17;
  bad_sum.insert(first_row, "0, 0.5, ");
  ExpectInputError(mesh, write("sum.json", bad_sum), "sum");
  std::string bad_parent = good;
  bad_parent.replace(bad_parent.find("\"parent\": 0"), 11, "\"parent\": 7");
  ExpectInputError(mesh, write("parent.json", bad_parent), "earlier joint");
}

}  // namespace
}  // namespace confluent
