// Silhouette extraction against constructed ground truth: textured plate with an actor, a
// floor shadow and noise; green screen with spill; a learned background from a moving actor;
// mask clean-up; bad input.

#include "silhouette/silhouette.h"

#include <gtest/gtest.h>

#include <map>

#include "core/error.h"
#include "core/image_io.h"
#include "tests/silhouette/synthetic_scene.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {

using testing::ActorPlacement;
using testing::Iou;

constexpr int kWidth = 320;
constexpr int kHeight = 240;

// A frame of the textured studio with the actor, its floor shadow and sensor noise.
struct Scene {
  Image plate;       // noisy clean plate
  Image frame;       // noisy frame
  Image truth;       // actor mask
  Image shadow;      // where the shadow darkens the floor (outside the actor), 0/255
};

Scene MakeScene(const ActorPlacement& placement, unsigned seed, double noise = 2.0) {
  Scene scene;
  const Image clean = testing::MakeTexturedPlate(kWidth, kHeight, 7);
  scene.plate = clean;
  testing::AddNoise(&scene.plate, noise, 1000 + seed);
  scene.frame = clean;
  // The shadow falls behind and to the right of the feet, darkening the floor to 0.5.
  const double cx = placement.feet_x + 0.25 * placement.height_px, cy = placement.feet_y - 8;
  const double ax = 0.35 * placement.height_px, ay = 0.08 * placement.height_px;
  testing::DarkenEllipse(&scene.frame, cx, cy, ax, ay, 0.5);
  scene.truth = testing::DrawActor(&scene.frame, placement);
  testing::AddNoise(&scene.frame, noise, 2000 + seed);
  scene.shadow = Image(kWidth, kHeight, 1);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const double r2 = (x - cx) * (x - cx) / (ax * ax) + (y - cy) * (y - cy) / (ay * ay);
      if (r2 < 0.8 && !scene.truth.at<std::uint8_t>(x, y)) scene.shadow.at<std::uint8_t>(x, y) = 255;
    }
  return scene;
}

std::size_t CountOverlap(const Image& mask, const Image& region) {
  std::size_t count = 0;
  for (std::size_t i = 0; i < mask.data.size(); ++i) count += mask.data[i] && region.data[i];
  return count;
}

std::size_t CountSet(const Image& mask) {
  std::size_t count = 0;
  for (std::uint8_t v : mask.data) count += v != 0;
  return count;
}

// An extractor reading frames from a vector.
SilhouetteExtractor MakeExtractor(const std::vector<Image>& frames, const std::string& plate_path,
                                  const SilhouetteOptions& options, int first_frame = 0) {
  return SilhouetteExtractor("cam00", plate_path, [&frames](int k) { return frames.at(k); },
                             static_cast<int>(frames.size()), first_frame, options);
}

TEST(BackgroundModel, ShadowsAndHighlightsAreBackgroundButColourChangesAreNot) {
  Image plate(64, 48, 3);
  for (int i = 0; i < 64 * 48; ++i) {
    plate.data[3 * i] = 160;
    plate.data[3 * i + 1] = 120;
    plate.data[3 * i + 2] = 90;
  }
  testing::AddNoise(&plate, 2.0, 1);
  BackgroundModelOptions options;
  const BackgroundModel model = BackgroundModel::FromPlates({plate}, options);
  EXPECT_NEAR(model.noise_sigma(), 2.0, 0.5);
  auto classify = [&](std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    Image frame(64, 48, 3);
    for (int i = 0; i < 64 * 48; ++i) {
      frame.data[3 * i] = r;
      frame.data[3 * i + 1] = g;
      frame.data[3 * i + 2] = b;
    }
    testing::AddNoise(&frame, 2.0, 2);
    Image labels;
    const Image mask = model.Classify(frame, &labels);
    std::map<int, int> histogram;
    for (std::uint8_t label : labels.data) ++histogram[label];
    int best = 0;
    for (const auto& [label, count] : histogram)
      if (count > histogram[best]) best = label;
    EXPECT_EQ(CountSet(mask) > 0.9 * 64 * 48, best == static_cast<int>(PixelClass::kForeground));
    return static_cast<PixelClass>(best);
  };
  EXPECT_EQ(classify(160, 120, 90), PixelClass::kBackground);
  EXPECT_EQ(classify(96, 72, 54), PixelClass::kShadow);       // 0.6 x the plate
  EXPECT_EQ(classify(184, 138, 104), PixelClass::kHighlight); // 1.15 x
  EXPECT_EQ(classify(48, 36, 27), PixelClass::kForeground);   // 0.3 x: too dark for a shadow
  EXPECT_EQ(classify(220, 165, 124), PixelClass::kForeground);  // 1.38 x: too bright
  EXPECT_EQ(classify(140, 130, 90), PixelClass::kForeground); // same brightness, other hue
}

TEST(BackgroundModel, PlateOfAnotherSizeIsInputErrorNamingTheFile) {
  testing::TempDir dir;
  const std::string plate_path = dir / "background_cam00.png";
  WriteImage(plate_path, testing::MakeTexturedPlate(kWidth / 2, kHeight / 2, 1));
  const Scene scene = MakeScene({}, 1);
  const std::vector<Image> frames = {scene.frame};
  try {
    MakeExtractor(frames, plate_path, SilhouetteOptions{});
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_EQ(error.path(), plate_path);
    EXPECT_NE(std::string(error.what()).find("160x120"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("320x240"), std::string::npos) << error.what();
  }
}

TEST(Silhouette, PlateWithShadowAndNoiseMatchesGroundTruth) {
  testing::TempDir dir;
  const std::vector<ActorPlacement> placements = {{160, 220, 170, false}, {110, 200, 150, true}, {220, 230, 185, false}};
  for (std::size_t k = 0; k < placements.size(); ++k) {
    const Scene scene = MakeScene(placements[k], static_cast<unsigned>(k));
    const std::string plate_path = dir / ("plate" + std::to_string(k) + ".png");
    WriteImage(plate_path, scene.plate);
    const std::vector<Image> frames = {scene.frame};
    SilhouetteExtractor extractor = MakeExtractor(frames, plate_path, SilhouetteOptions{});
    EXPECT_EQ(extractor.info().method, SilhouetteMethod::kPlate);
    EXPECT_TRUE(extractor.info().warnings.empty());
    MaskSummary summary;
    const Image mask = extractor.Extract(scene.frame, 0, &summary);
    const double iou = Iou(mask, scene.truth);
    EXPECT_GE(iou, 0.98) << "placement " << k;
    // The shadow stays background.
    const std::size_t shadow_pixels = CountSet(scene.shadow);
    ASSERT_GT(shadow_pixels, 500u);
    EXPECT_LT(CountOverlap(mask, scene.shadow), shadow_pixels / 100) << "placement " << k;
    EXPECT_FALSE(summary.flagged()) << "placement " << k;
    EXPECT_NEAR(summary.foreground_fraction, static_cast<double>(CountSet(scene.truth)) / (kWidth * kHeight), 0.005);
    if (placements[k].hand_detached) {
      const double scale = placements[k].height_px / 170.0;
      const int hand_x = static_cast<int>(std::lround(placements[k].feet_x + 50 * scale));
      const int hand_y = static_cast<int>(std::lround(placements[k].feet_y - 60 * scale));
      ASSERT_EQ(scene.truth.at<std::uint8_t>(hand_x, hand_y), 255);
      EXPECT_EQ(mask.at<std::uint8_t>(hand_x, hand_y), 255) << "the detached hand is kept";
    }
  }
}

TEST(Silhouette, WithoutShadowModelTheShadowWouldBeForeground) {
  // Guards the test above: a plain colour-difference threshold would take the shadow.
  const Scene scene = MakeScene({}, 3);
  std::size_t differing = 0;
  for (std::size_t i = 0; i < scene.shadow.data.size(); ++i) {
    if (!scene.shadow.data[i]) continue;
    int d = 0;
    for (int c = 0; c < 3; ++c) d += std::abs(scene.frame.data[3 * i + c] - scene.plate.data[3 * i + c]);
    differing += d > 60;
  }
  EXPECT_GT(differing, CountSet(scene.shadow) / 2);
}

TEST(MaskCleanup, KeepsNearbyPartsDropsSpeckleAndFillsSmallHoles) {
  Image raw(200, 160, 1);
  auto fill_rect = [&](int x0, int y0, int x1, int y1, std::uint8_t value) {
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) raw.at<std::uint8_t>(x, y) = value;
  };
  fill_rect(80, 30, 120, 150, 255);   // body, 4800 px
  fill_rect(136, 90, 146, 100, 255);  // hand 16 px away, 100 px
  fill_rect(10, 10, 14, 14, 255);     // speckle far away
  fill_rect(180, 140, 190, 150, 255); // a far blob of 100 px
  fill_rect(95, 60, 99, 64, 0);       // small hole, 16 px
  fill_rect(85, 100, 115, 130, 0);    // large hole (a gap between arm and body), 900 px
  raw.at<std::uint8_t>(150, 20) = 255;  // single-pixel speckle
  for (int scale : {1, 2}) {
    SCOPED_TRACE("work scale " + std::to_string(scale));
    MaskCleanupOptions options;
    options.work_scale = scale;
    MaskCleanupStats stats;
    const Image mask = CleanMask(raw, options, &stats);
    EXPECT_EQ(stats.parts_kept, 2);
    EXPECT_EQ(mask.at<std::uint8_t>(141, 95), 255) << "hand kept";
    EXPECT_EQ(mask.at<std::uint8_t>(12, 12), 0) << "speckle dropped";
    EXPECT_EQ(mask.at<std::uint8_t>(185, 145), 0) << "far blob dropped";
    EXPECT_EQ(mask.at<std::uint8_t>(97, 62), 255) << "small hole filled";
    EXPECT_EQ(mask.at<std::uint8_t>(100, 115), 0) << "large hole kept";
    EXPECT_EQ(mask.at<std::uint8_t>(100, 40), 255);
    // The boundary stays at full resolution: the body's edges are exact.
    EXPECT_EQ(mask.at<std::uint8_t>(80, 70), 255);
    EXPECT_EQ(mask.at<std::uint8_t>(79, 70), 0);
    EXPECT_EQ(mask.at<std::uint8_t>(119, 70), 255);
    EXPECT_EQ(mask.at<std::uint8_t>(120, 70), 0);
  }
}

TEST(Silhouette, GreenScreenWithSpillIsKeyedAutomatically) {
  for (unsigned seed : {1u, 2u}) {
    Image frame = testing::MakeGreenScreen(kWidth, kHeight, seed);
    ActorPlacement placement;
    placement.feet_x = 140 + 30 * seed;
    const Image truth = testing::DrawActor(&frame, placement, 0.25);  // green spill on the edges
    testing::AddNoise(&frame, 2.0, seed);
    const std::vector<Image> frames = {frame};
    SilhouetteExtractor extractor = MakeExtractor(frames, "", SilhouetteOptions{});  // auto, no plate
    EXPECT_EQ(extractor.info().method, SilhouetteMethod::kGreen);
    EXPECT_GE(extractor.info().greenness, 0.08);
    EXPECT_LE(extractor.info().greenness, 0.3);
    MaskSummary summary;
    const Image mask = extractor.Extract(frame, 0, &summary);
    EXPECT_GE(Iou(mask, truth), 0.98) << "seed " << seed;
    EXPECT_FALSE(summary.flagged());
  }
}

TEST(Silhouette, LearnedBackgroundFromMovingActor) {
  const Image clean = testing::MakeTexturedPlate(kWidth, kHeight, 7);
  std::vector<Image> frames, truths;
  for (int k = 0; k < 24; ++k) {
    Image frame = clean;
    ActorPlacement placement;
    placement.feet_x = 50 + 220.0 * k / 23;
    placement.feet_y = 215 + 10 * std::sin(0.5 * k);
    truths.push_back(testing::DrawActor(&frame, placement));
    testing::AddNoise(&frame, 2.0, 100 + k);
    frames.push_back(std::move(frame));
  }
  SilhouetteOptions options;
  options.method = SilhouetteMethod::kLearned;
  SilhouetteExtractor extractor = MakeExtractor(frames, "", options);
  EXPECT_EQ(extractor.info().method, SilhouetteMethod::kLearned);
  double worst = 1, sum = 0;
  for (int k = 0; k < 24; ++k) {
    MaskSummary summary;
    const double iou = Iou(extractor.Extract(frames[k], k, &summary), truths[k]);
    worst = std::min(worst, iou);
    sum += iou;
  }
  EXPECT_GE(sum / 24, 0.98);
  EXPECT_GE(worst, 0.95);
}

TEST(Silhouette, MissingPlateFallsBackToLearnedWithWarning) {
  const Image clean = testing::MakeTexturedPlate(kWidth, kHeight, 7);
  std::vector<Image> frames, truths;
  for (int k = 0; k < 12; ++k) {
    Image frame = clean;
    ActorPlacement placement;
    placement.feet_x = 60 + 200.0 * k / 11;
    truths.push_back(testing::DrawActor(&frame, placement));
    testing::AddNoise(&frame, 2.0, 300 + k);
    frames.push_back(std::move(frame));
  }
  SilhouetteOptions options;
  options.method = SilhouetteMethod::kPlate;
  SilhouetteExtractor extractor = MakeExtractor(frames, "", options);
  EXPECT_EQ(extractor.info().method, SilhouetteMethod::kLearned);
  ASSERT_FALSE(extractor.info().warnings.empty());
  EXPECT_NE(extractor.info().warnings[0].find("no clean plate"), std::string::npos) << extractor.info().warnings[0];
  MaskSummary summary;
  EXPECT_GE(Iou(extractor.Extract(frames[5], 5, &summary), truths[5]), 0.95);
}

TEST(Silhouette, BlackAndWhiteFramesAreFlaggedWithoutCrashing) {
  testing::TempDir dir;
  const Scene scene = MakeScene({}, 4);
  const std::string plate_path = dir / "plate.png";
  WriteImage(plate_path, scene.plate);
  Image black(kWidth, kHeight, 3), white(kWidth, kHeight, 3);
  std::fill(white.data.begin(), white.data.end(), 255);
  const std::vector<Image> frames = {scene.frame, black, white, scene.frame};
  SilhouetteExtractor extractor = MakeExtractor(frames, plate_path, SilhouetteOptions{});
  MaskSummary summary;
  extractor.Extract(frames[0], 0, &summary);
  EXPECT_FALSE(summary.flagged());
  for (int k : {1, 2}) {
    const Image mask = extractor.Extract(frames[k], k, &summary);
    EXPECT_TRUE(summary.empty || summary.full) << "frame " << k << " fraction " << summary.foreground_fraction;
    EXPECT_TRUE(summary.flagged());
    EXPECT_EQ(mask.width, kWidth);
  }
  extractor.Extract(frames[3], 3, &summary);
  EXPECT_TRUE(summary.area_jump) << "back from a full mask";
  // Green keying of a black frame (no plate) gives a mask too: never a crash.
  SilhouetteOptions green;
  green.method = SilhouetteMethod::kGreen;
  const std::vector<Image> dark = {black};
  SilhouetteExtractor keyer = MakeExtractor(dark, "", green);
  keyer.Extract(black, 0, &summary);
  EXPECT_TRUE(summary.empty || summary.full);
}

TEST(Silhouette, SummaryFlagsBorderAndAreaJump) {
  SilhouetteOptions options;
  Image mask(100, 80, 1);
  for (int y = 20; y < 60; ++y)
    for (int x = 30; x < 50; ++x) mask.at<std::uint8_t>(x, y) = 255;
  MaskSummary summary = SummarizeMask(mask, -1, options);
  EXPECT_NEAR(summary.foreground_fraction, 800.0 / 8000.0, 1e-12);
  EXPECT_FALSE(summary.flagged());
  summary = SummarizeMask(mask, 0.1 * 0.5, options);
  EXPECT_TRUE(summary.area_jump);  // doubled
  summary = SummarizeMask(mask, 0.1 * 0.9, options);
  EXPECT_FALSE(summary.area_jump);
  for (int y = 60; y < 80; ++y) mask.at<std::uint8_t>(40, y) = 255;  // reaches the bottom edge
  summary = SummarizeMask(mask, -1, options);
  EXPECT_TRUE(summary.touches_border);
  EXPECT_TRUE(SummarizeMask(Image(100, 80, 1), -1, options).empty);
}

TEST(Silhouette, Mog2WithPlateFindsTheActor) {
  testing::TempDir dir;
  const Scene scene = MakeScene({}, 5);
  const std::string plate_path = dir / "plate.png";
  WriteImage(plate_path, scene.plate);
  SilhouetteOptions options;
  options.method = SilhouetteMethod::kMog2;
  const std::vector<Image> frames = {scene.frame};
  SilhouetteExtractor extractor = MakeExtractor(frames, plate_path, options);
  EXPECT_EQ(extractor.info().method, SilhouetteMethod::kMog2);
  MaskSummary summary;
  EXPECT_GE(Iou(extractor.Extract(scene.frame, 0, &summary), scene.truth), 0.85);
}

TEST(SilhouetteOptions, CheckRejectsBadValues) {
  SilhouetteOptions options;
  EXPECT_NO_THROW(options.Check());
  options.cleanup.work_scale = 3;
  EXPECT_THROW(options.Check(), UsageError);
  options = {};
  options.background.shadow_min_brightness = 1.2;
  EXPECT_THROW(options.Check(), UsageError);
  options = {};
  options.full_fraction = 0;
  EXPECT_THROW(options.Check(), UsageError);
  EXPECT_THROW(ParseSilhouetteMethod("magic"), UsageError);
  EXPECT_EQ(ParseSilhouetteMethod("green"), SilhouetteMethod::kGreen);
}

}  // namespace
}  // namespace confluent
