// The core options refuse invalid values with a UsageError that names the field and the value.
#include <gtest/gtest.h>

#include <cmath>

#include "core/bvh_retarget.h"
#include "core/error.h"
#include "core/video_writer.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(CoreOptions, CheckNamesTheFieldAndTheValue) {
  EXPECT_NO_THROW(VideoWriterOptions().Check());
  EXPECT_NO_THROW(BvhRetargetOptions().Check());
  VideoWriterOptions video;
  video.crf = 52;
  testing::ExpectCheckRefuses(video, "VideoWriterOptions.crf = 52: must be in 0..51");
  video = VideoWriterOptions();
  video.fps = std::nan("");
  testing::ExpectCheckRefuses(video, "VideoWriterOptions.fps = nan: must be in (0, 1000]");
  video = VideoWriterOptions();
  video.preset = "";
  testing::ExpectCheckRefuses(video, "VideoWriterOptions.preset = '': must not be empty");
  BvhRetargetOptions retarget;
  retarget.up_axis = 'x';
  testing::ExpectCheckRefuses(retarget, "BvhRetargetOptions.up_axis = 'x': must be");
  retarget = BvhRetargetOptions();
  retarget.min_hinge_turn_rad = -0.1;
  testing::ExpectCheckRefuses(retarget, "BvhRetargetOptions.min_hinge_turn_rad = -0.1");
}

TEST(CoreOptions, VectorsAndPairsOfFieldsAreNamedWithTheirValues) {
  try {
    RequireOption(false, "X.colour", {0.5, 1.0, 2.0}, "finite");
    ADD_FAILURE() << "accepted";
  } catch (const UsageError& error) {
    EXPECT_STREQ(error.what(), "X.colour = (0.5, 1, 2): must be finite");
  }
  try {
    RequireOptions(false, "X.near_m", 2.0, "X.far_m", 1.5, "near_m < far_m");
    ADD_FAILURE() << "accepted";
  } catch (const UsageError& error) {
    EXPECT_STREQ(error.what(), "X.near_m = 2 and X.far_m = 1.5: must be near_m < far_m");
  }
  EXPECT_NO_THROW(RequireOption(true, "X.colour", {0.0, 0.0, 0.0}, "finite"));
  EXPECT_NO_THROW(RequireOptions(true, "X.a", 1.0, "X.b", 2.0, "a < b"));
}

}  // namespace
}  // namespace confluent
