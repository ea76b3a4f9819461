// The studio options refuse invalid values with a UsageError that names the field and the value.
#include <gtest/gtest.h>

#include <limits>

#include "core/error.h"
#include "studio/actor.h"
#include "studio/rig.h"
#include "studio/synth.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(StudioOptions, CheckNamesTheFieldAndTheValue) {
  EXPECT_NO_THROW(StudioRigOptions().Check());
  EXPECT_NO_THROW(StudioActorOptions().Check());
  StudioRigOptions rig;
  rig.num_ring_cameras = 0;
  testing::ExpectCheckRefuses(rig, "StudioRigOptions.num_ring_cameras = 0: must be in [1, 256]");
  rig = StudioRigOptions();
  rig.heldout_radius_m = 0.25;
  testing::ExpectCheckRefuses(rig, "StudioRigOptions.heldout_radius_m = 0.25: must be > 0.5 metres");
  rig = StudioRigOptions();
  rig.target_in_world.z() = std::numeric_limits<double>::infinity();
  testing::ExpectCheckRefuses(rig, "StudioRigOptions.target_in_world = (0, 0, inf): must be finite");
  StudioActorOptions actor;
  actor.arm_girth = 3.0;
  testing::ExpectCheckRefuses(actor, "StudioActorOptions.arm_girth = 3: must be in [0.5, 2]");
  StudioSynthOptions synth;
  synth.capture_dir = "/tmp/unused";
  synth.actor_mesh_path = "actor.ply";
  testing::ExpectCheckRefuses(synth,
                              "StudioSynthOptions.actor_mesh_path = 'actor.ply' and StudioSynthOptions.actor_skin_path "
                              "= '': must be given together (--actor-mesh and --actor-skin");
}

}  // namespace
}  // namespace confluent
