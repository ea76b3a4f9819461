// The deformation options refuse invalid values with a UsageError that names the field and the
// value (no abort).
#include <gtest/gtest.h>

#include "core/error.h"
#include "deform/confluent_motion.h"
#include "deform/correspondence_placement.h"
#include "deform/correspondences.h"
#include "deform/laplacian.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(DeformOptions, CheckNamesTheFieldAndTheValue) {
  EXPECT_NO_THROW(ConfluentMotionOptions().Check());
  EXPECT_NO_THROW(AugmentOptions().Check());
  EXPECT_NO_THROW(CotanLaplacianOptions().Check());
  ConfluentMotionOptions motion;
  motion.singular_w = 1.5;
  testing::ExpectCheckRefuses(motion, "ConfluentMotionOptions.singular_w = 1.5: must be in [0, 1)");
  motion = ConfluentMotionOptions();
  motion.threads = 0;
  testing::ExpectCheckRefuses(motion, "ConfluentMotionOptions.threads = 0: must be >= 1");
  motion = ConfluentMotionOptions();
  motion.laplacian.mollify_factor = -0.25;
  testing::ExpectCheckRefuses(motion, "CotanLaplacianOptions.mollify_factor = -0.25");
  AugmentOptions augment;
  augment.max_radius_factor = 0.5;
  testing::ExpectCheckRefuses(augment, "AugmentOptions.max_radius_factor = 0.5: must be > 1");
  CorrespondencePlacementOptions placement;
  placement.limb_ring_markers = 2;
  testing::ExpectCheckRefuses(placement, "CorrespondencePlacementOptions.limb_ring_markers = 2: must be >= 3");
}

}  // namespace
}  // namespace confluent
