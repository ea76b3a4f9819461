// Dark shoes on a dark floor beside a deep shadow: the masks have lost the shoes (as the graph
// cut loses them), and RestoreFeetBelowHull puts them back from below the hull without taking
// the shadow.

#include <gtest/gtest.h>

#include <cstdio>

#include "core/error.h"
#include "silhouette/background_model.h"
#include "silhouette/feet_restore.h"
#include "silhouette/multiview.h"
#include "tests/silhouette/multiview_scene.h"
#include "tests/silhouette/synthetic_scene.h"

namespace confluent {
namespace {

constexpr int kFrameWidth = 320, kFrameHeight = 240;

// The actor of MakeActor with legs that end at the ankles (8 cm) and navy shoes below them.
std::vector<testing::Ellipsoid> ActorWithoutShoes() {
  std::vector<testing::Ellipsoid> actor = testing::MakeActor(0.0, 0.0, 0.3);
  for (int leg : {0, 1}) {
    actor[leg].center.z() = 0.5;
    actor[leg].radii.z() = 0.42;
  }
  return actor;
}

std::vector<testing::Ellipsoid> Shoes() {
  const Eigen::Vector3d navy(30, 35, 80);
  return {{{-0.1, 0.05, 0.045}, {0.06, 0.13, 0.045}, navy}, {{0.1, 0.05, 0.045}, {0.06, 0.13, 0.045}, navy}};
}

// A brown floor, slightly textured, and its plate darkened to 30% where the actor's shadow lies
// on the floor (an ellipse beside the feet).
Image Floor(const Camera& camera, bool shadow, unsigned seed) {
  Image image(kFrameWidth, kFrameHeight, 3);
  const Eigen::Vector3d origin = camera.center_in_world();
  for (int y = 0; y < kFrameHeight; ++y)
    for (int x = 0; x < kFrameWidth; ++x) {
      const unsigned hash = (x * 73856093u) ^ (y * 19349663u) ^ (seed * 83492791u);
      const int grain = static_cast<int>(hash % 9) - 4;
      double factor = 1.0;
      const Eigen::Vector3d ray = camera.RayInWorld(Eigen::Vector2d(x, y));
      if (shadow && ray.z() < 0) {
        const Eigen::Vector3d floor = origin - ray * (origin.z() / ray.z());
        const double u = (floor.x() - 0.25) / 0.35, v = (floor.y() - 0.2) / 0.3;
        if (u * u + v * v < 1) factor = 0.3;
      }
      image.at<std::uint8_t>(x, y, 0) = static_cast<std::uint8_t>(factor * (95 + grain));
      image.at<std::uint8_t>(x, y, 1) = static_cast<std::uint8_t>(factor * (65 + grain));
      image.at<std::uint8_t>(x, y, 2) = static_cast<std::uint8_t>(factor * (42 + grain));
    }
  return image;
}

struct FeetScene {
  Rig rig = testing::MakeRingRig(8, kFrameWidth, kFrameHeight);
  std::vector<Image> frames, without_shoes, shoes, shadow;
  std::vector<BackgroundModel> models;
  HullUnderside underside;
  FeetScene() {
    std::vector<testing::Ellipsoid> whole = ActorWithoutShoes();
    for (const testing::Ellipsoid& shoe : Shoes()) whole.push_back(shoe);
    for (int c = 0; c < rig.size(); ++c) {
      const Camera& camera = rig.cameras[c];
      const Image plate = Floor(camera, false, c);
      Image frame = testing::RenderFrame(camera, whole, Floor(camera, true, c));
      testing::AddNoise(&frame, 1.5, 7 + c);
      frames.push_back(frame);
      const Image body = testing::RenderMask(camera, ActorWithoutShoes());
      Image shoe = testing::RenderMask(camera, whole);
      for (std::size_t i = 0; i < shoe.data.size(); ++i) shoe.data[i] = shoe.data[i] && !body.data[i] ? 255 : 0;
      without_shoes.push_back(body);
      shoes.push_back(shoe);
      // The shadow's visible pixels: darker than the plate and not the actor.
      const Image dark = Floor(camera, true, c);
      const Image actor = testing::RenderMask(camera, whole);
      Image visible_shadow(kFrameWidth, kFrameHeight, 1);
      for (std::size_t i = 0; i < visible_shadow.data.size(); ++i)
        visible_shadow.data[i] = !actor.data[i] && dark.data[i * 3] < plate.data[i * 3] ? 255 : 0;
      shadow.push_back(visible_shadow);
      models.push_back(BackgroundModel::FromPlates({plate}, {}, "plate"));
    }
    std::vector<Image> masks = without_shoes;
    CheckMultiView(rig, &masks, {}, MultiViewOptions{}, nullptr, nullptr, &underside);
  }
  struct Counts {
    long shoe_total = 0, shoe_added = 0, shadow_added = 0, other_added = 0;
  };
  Counts Restore(const FeetRestoreOptions& options) const {
    Counts counts;
    for (int c = 0; c < rig.size(); ++c) {
      Image mask = without_shoes[c];
      const int added = RestoreFeetBelowHull(&mask, frames[c], rig.cameras[c], underside, models[c], options);
      long counted = 0;
      for (std::size_t i = 0; i < mask.data.size(); ++i) {
        counts.shoe_total += shoes[c].data[i] != 0;
        if (mask.data[i] == without_shoes[c].data[i]) continue;
        ++counted;
        if (shoes[c].data[i]) ++counts.shoe_added;
        else if (shadow[c].data[i]) ++counts.shadow_added;
        else ++counts.other_added;
      }
      EXPECT_EQ(counted, added) << rig.cameras[c].name;
    }
    return counts;
  }
};

TEST(FeetRestore, DarkShoesComeBackAndTheirShadowDoesNot) {
  const FeetScene scene;
  ASSERT_FALSE(scene.underside.lowest.empty());
  const FeetScene::Counts restored = scene.Restore(FeetRestoreOptions{});
  FeetRestoreOptions any_colour;
  any_colour.min_chroma_angle_deg = 0;  // every foreground pixel below the hull
  const FeetScene::Counts unchecked = scene.Restore(any_colour);
  std::printf("shoes %ld px: restored %ld (shadow %ld, other %ld); without the colour test %ld (shadow %ld, other %ld)\n",
              restored.shoe_total, restored.shoe_added, restored.shadow_added, restored.other_added,
              unchecked.shoe_added, unchecked.shadow_added, unchecked.other_added);
  ASSERT_GT(restored.shoe_total, 500);
  // Measured: 1477 of 2020 (823 with reach 0: the columns alone lie under the ankles, not the toes).
  EXPECT_GE(restored.shoe_added, 0.65 * restored.shoe_total);
  EXPECT_LE(restored.shadow_added + restored.other_added, 0.02 * restored.shoe_added);
  EXPECT_GT(unchecked.shadow_added, 10 * (restored.shadow_added + 1));  // the colour test is what keeps the shadow out
}

TEST(FeetRestore, DisabledOrSizeMismatch) {
  const FeetScene scene;
  FeetRestoreOptions off;
  off.enabled = false;
  Image mask = scene.without_shoes[0];
  EXPECT_EQ(RestoreFeetBelowHull(&mask, scene.frames[0], scene.rig.cameras[0], scene.underside, scene.models[0], off), 0);
  Image small(10, 10, 1);
  EXPECT_THROW(RestoreFeetBelowHull(&small, scene.frames[0], scene.rig.cameras[0], scene.underside, scene.models[0], {}),
               UsageError);
  FeetRestoreOptions bad;
  bad.min_chroma_angle_deg = 90;
  EXPECT_THROW(bad.Check(), UsageError);
}

}  // namespace
}  // namespace confluent
