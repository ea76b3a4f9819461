// The render options refuse invalid values with a UsageError that names the field and the value.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "render/camera_path.h"
#include "render/cpu_raster.h"
#include "render/projective_texture.h"
#include "render/renderer.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

TEST(RenderOptions, CheckNamesTheFieldAndTheValue) {
  EXPECT_NO_THROW(ProjectiveTextureOptions().Check());
  EXPECT_NO_THROW(ShadingOptions().Check());
  ProjectiveTextureOptions texture;
  texture.best_k = 9;
  testing::ExpectCheckRefuses(texture, "ProjectiveTextureOptions.best_k = 9: must be in 1..8");
  texture = ProjectiveTextureOptions();
  texture.visibility_scale = 1.5;
  testing::ExpectCheckRefuses(texture, "ProjectiveTextureOptions.visibility_scale = 1.5: must be in (0, 1]");
  texture = ProjectiveTextureOptions();
  texture.fallback_color.y() = std::nan("");
  testing::ExpectCheckRefuses(texture, "ProjectiveTextureOptions.fallback_color = (0.5, nan, 0.5): must be finite");
  ShadingOptions shading;
  shading.light_direction_in_world.setZero();
  testing::ExpectCheckRefuses(shading,
                              "ShadingOptions.light_direction_in_world = (0, 0, 0): must be a finite non-zero vector");
  shading = ShadingOptions();
  shading.color_type = PixelType::kUInt16;
  testing::ExpectCheckRefuses(shading, "ShadingOptions.color_type = 'kUInt16': must be kUInt8 or kFloat32");
  CpuRasterOptions raster;
  raster.near_m = 2.0;
  raster.far_m = 1.0;
  testing::ExpectCheckRefuses(raster, "CpuRasterOptions.near_m = 2 and CpuRasterOptions.far_m = 1: must be");
  OrbitPathOptions orbit;
  orbit.num_frames = 0;
  testing::ExpectCheckRefuses(orbit, "OrbitPathOptions.num_frames = 0: must be >= 1");
}

}  // namespace
}  // namespace confluent
