// The silhouette options refuse invalid values with a UsageError that names the field and the value.
#include <gtest/gtest.h>

#include "core/error.h"
#include "silhouette/silhouette.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(SilhouetteOptions, CheckNamesTheFieldAndTheValue) {
  SilhouetteOptions options;
  options.cleanup.work_scale = 3;
  testing::ExpectCheckRefuses(options, "MaskCleanupOptions.work_scale = 3: must be 0 (automatic), 1, 2 or 4");
  options = SilhouetteOptions();
  options.background.shadow_min_brightness = 1.2;
  testing::ExpectCheckRefuses(options, "BackgroundModelOptions.shadow_min_brightness = 1.2: must be in [0, 1)");
  options = SilhouetteOptions();
  options.chroma.auto_min_greenness = 0.6;
  options.chroma.auto_max_greenness = 0.4;
  testing::ExpectCheckRefuses(
      options, "ChromaKeyOptions.auto_min_greenness = 0.6 and ChromaKeyOptions.auto_max_greenness = 0.4: must be");
  options = SilhouetteOptions();
  options.full_fraction = 0;
  testing::ExpectCheckRefuses(options, "SilhouetteOptions.full_fraction = 0: must be 0 <= empty_fraction");
  options = SilhouetteOptions();
  options.threads = 0;
  testing::ExpectCheckRefuses(options, "SilhouetteOptions.threads = 0: must be in [1, 256]");
  options = SilhouetteOptions();
  options.person_prior.reach = -0.1;
  testing::ExpectCheckRefuses(options, "PersonPriorOptions.reach = -0.1: must be in [0, 1]");
  EXPECT_EQ(ParsePersonPriorUse("off"), PersonPriorUse::kOff);
  EXPECT_THROW(ParsePersonPriorUse("yes"), UsageError);
}

}  // namespace
}  // namespace confluent
