// The refinement options refuse invalid values with a UsageError that names the field and the
// value (no abort).
#include <gtest/gtest.h>

#include "core/error.h"
#include "core/mesh_ops.h"
#include "refine/normalised_diffusion.h"
#include "refine/photo_refinement.h"
#include "refine/silhouette_refinement.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(RefineOptions, CheckNamesTheFieldAndTheValue) {
  EXPECT_NO_THROW(SilhouetteRefinementOptions().Check());
  EXPECT_NO_THROW(PhotoRefinementOptions().Check());
  SilhouetteRefinementOptions silhouette;
  silhouette.max_rim_cosine = 1.0;
  testing::ExpectCheckRefuses(silhouette, "SilhouetteRefinementOptions.max_rim_cosine = 1: must be in (0, 1)");
  silhouette = SilhouetteRefinementOptions();
  silhouette.iterations = -3;
  testing::ExpectCheckRefuses(silhouette, "SilhouetteRefinementOptions.iterations = -3");
  PhotoRefinementOptions photo;
  photo.neighbours = 0;
  testing::ExpectCheckRefuses(photo, "PhotoRefinementOptions.neighbours = 0: must be >= 1");
  photo = PhotoRefinementOptions();
  photo.max_flow_px = -2.5;
  testing::ExpectCheckRefuses(photo, "PhotoRefinementOptions.max_flow_px = -2.5: must be > 0");
  photo = PhotoRefinementOptions();
  photo.full_resolution_rounds = -1;
  testing::ExpectCheckRefuses(photo, "PhotoRefinementOptions.full_resolution_rounds = -1: must be >= 0");
  photo = PhotoRefinementOptions();
  photo.full_resolution_spread_stiffness = 0.0;
  testing::ExpectCheckRefuses(photo, "PhotoRefinementOptions.full_resolution_spread_stiffness = 0: must be > 0");
  photo = PhotoRefinementOptions();
  photo.full_resolution_patch_stride = 0;
  testing::ExpectCheckRefuses(photo, "PhotoRefinementOptions.full_resolution_patch_stride = 0: must be >= 1");
  photo = PhotoRefinementOptions();
  photo.full_resolution_variational_iterations = -2;
  testing::ExpectCheckRefuses(photo, "PhotoRefinementOptions.full_resolution_variational_iterations = -2: must be >= 0");
  EXPECT_THROW(NormalisedDiffusion(MakeUvSphere(1.0, 6, 12), 0.0, "sphere"), UsageError);
}

}  // namespace
}  // namespace confluent
