// The tracking options refuse invalid values with a UsageError that names the field and the value.
#include <gtest/gtest.h>

#include "core/error.h"
#include "tracking/scan_registration.h"
#include "tracking/tracker.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(TrackingOptions, CheckNamesTheFieldAndTheValue) {
  EXPECT_NO_THROW(TrackerOptions().Check());
  EXPECT_NO_THROW(ScanRegistrationOptions().Check());
  TrackerOptions tracker;
  tracker.init_rounds = 0;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.init_rounds = 0: must be >= 1");
  tracker = TrackerOptions();
  tracker.init_max_iterations = 0;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.init_max_iterations = 0: must be >= 1");
  tracker = TrackerOptions();
  tracker.velocity_damping = 2.0;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.velocity_damping = 2: must be in [0, 1.5]");
  tracker = TrackerOptions();
  tracker.girth_inflation_max = 0.6;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.girth_inflation_max = 0.6: must be in [0, 0.5]");
  tracker = TrackerOptions();
  tracker.girth_inflation_below_iou = 1.5;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.girth_inflation_below_iou = 1.5: must be in [0, 1]");
  tracker = TrackerOptions();
  tracker.skirt_search.length_step_m = 0.0;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.skirt_search.length_step_m = 0: must be > 0");
  tracker = TrackerOptions();
  tracker.skirt_search.refinements = -1;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.skirt_search.refinements = -1: must be in [0, 8]");
  tracker = TrackerOptions();
  tracker.skirt_search.min_gain = 1.0;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.skirt_search.min_gain = 1: must be in [0, 1)");
  tracker = TrackerOptions();
  tracker.fit.downscale = 17;
  testing::ExpectCheckRefuses(tracker, "SilhouetteFitOptions.downscale = 17: must be in [0, 16]");
  tracker = TrackerOptions();
  tracker.fit.rest_prior_scale = -1;
  testing::ExpectCheckRefuses(tracker, "SilhouetteFitOptions.rest_prior_scale = -1: must be >= 0");
  tracker = TrackerOptions();
  tracker.init_rest_pull_min_iou_gain = 1;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.init_rest_pull_min_iou_gain = 1: must be in [0, 1)");
  tracker = TrackerOptions();
  tracker.limb_search_repeat_rise = 0.9;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.limb_search_repeat_rise = 0.9: must be >= 1");
  tracker = TrackerOptions();
  tracker.shape_samples = -1;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.shape_samples = -1: must be >= 0");
  tracker = TrackerOptions();
  tracker.shape_sample_every = 0;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.shape_sample_every = 0: must be >= 1");
  tracker = TrackerOptions();
  tracker.arm_twist_every = -1;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.arm_twist_every = -1: must be >= 0");
  tracker = TrackerOptions();
  tracker.arm_twist_bend_rad = -1;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.arm_twist_bend_rad = -1: must be >= 0");
  tracker = TrackerOptions();
  tracker.hand_rebend_flex_deg = {0, 200};
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.hand_rebend_flex_deg = 200: must be in [-180, 180]");
  tracker = TrackerOptions();
  tracker.hand_rebend_min_rad = -1;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.hand_rebend_min_rad = -1: must be >= 0");
  tracker = TrackerOptions();
  tracker.limb_search_repeat_drop = -0.1;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.limb_search_repeat_drop = -0.1: must be in [0, 1)");
  tracker = TrackerOptions();
  tracker.landmark_hand_disagreement_rad = 0;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.landmark_hand_disagreement_rad = 0: must be > 0");
  tracker = TrackerOptions();
  tracker.landmark_hand_iou_tolerance = 1;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.landmark_hand_iou_tolerance = 1: must be in [0, 1)");
  tracker = TrackerOptions();
  tracker.landmark_hand_max_wrist_gap_m = -0.01;
  testing::ExpectCheckRefuses(tracker, "TrackerOptions.landmark_hand_max_wrist_gap_m = -0.01: must be > 0");
  ScanRegistrationOptions registration;
  registration.min_pair_distance_m = 0.2;
  registration.max_pair_distance_m = 0.1;
  testing::ExpectCheckRefuses(registration,
                              "ScanRegistrationOptions.min_pair_distance_m = 0.2 and "
                              "ScanRegistrationOptions.max_pair_distance_m = 0.1: must be");
}

}  // namespace
}  // namespace confluent
