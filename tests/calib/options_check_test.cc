// The calibration options refuse invalid values with a UsageError that names the field and the value.
#include <gtest/gtest.h>

#include "calib/calibrate.h"
#include "calib/checkerboard.h"
#include "calib/rig_check.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(CalibOptions, CheckNamesTheFieldAndTheValue) {
  EXPECT_NO_THROW(CalibrateOptions().Check());
  EXPECT_NO_THROW(RigCheckOptions().Check());
  testing::ExpectCheckRefuses(CheckerboardSpec{8, 1, 0.1}, "CheckerboardSpec.rows = 1: must be >= 2");
  testing::ExpectCheckRefuses(CheckerboardSpec{8, 6, -1.0}, "CheckerboardSpec.square_m = -1: must be > 0");
  CalibrateOptions calibrate;
  calibrate.huber_px = 0.0;
  testing::ExpectCheckRefuses(calibrate, "CalibrateOptions.huber_px = 0: must be > 0");
  calibrate = CalibrateOptions();
  calibrate.consensus_rotation_deg = 95.0;
  testing::ExpectCheckRefuses(calibrate, "CalibrateOptions.consensus_rotation_deg = 95: must be in (0, 90)");
  RigCheckOptions rig;
  rig.min_plausible_extent_m = 5.0;
  rig.max_plausible_extent_m = 2.0;
  testing::ExpectCheckRefuses(
      rig, "RigCheckOptions.min_plausible_extent_m = 5 and RigCheckOptions.max_plausible_extent_m = 2: must be");
}

}  // namespace
}  // namespace confluent
