// Real footage from ../shared/data (each test skips when it is absent): a green-screen dome
// with ground-truth silhouettes, a clean-plate room, and a cluttered lab without a plate.
// Contact sheets go to /tmp/confluent_silhouette_real/ for a person to look at.

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "calib/importers.h"
#include "calib/rig_check.h"
#include "core/image_io.h"
#include "core/video.h"
#include "silhouette/multiview.h"
#include "silhouette/overlay.h"
#include "silhouette/silhouette.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

const char* kSheetDir = "/tmp/confluent_silhouette_real";

Image Binarize(const Image& image) {
  const Image rgb = ToRgb8(image);
  Image mask(rgb.width, rgb.height, 1);
  for (std::size_t i = 0; i < mask.data.size(); ++i) mask.data[i] = rgb.data[3 * i] >= 128 ? 255 : 0;
  return mask;
}

TEST(RealSilhouettes, TsinghuaGreenScreenMatchesGroundTruth) {
  const std::string data = testing::SharedDataPath("real/tsinghua_lkB");
  if (data.empty()) GTEST_SKIP() << "../shared/data/real/tsinghua_lkB is absent";
  fs::create_directories(kSheetDir);
  double sum = 0, worst = 1;
  std::vector<Image> tiles;
  std::printf("camera  method  greenness   IoU\n");
  for (int k = 0; k < 20; ++k) {
    // Image k+1 <-> silhouette k <-> camera k (see ../shared/data/README.md).
    char image_name[64], mask_name[64], camera[16];
    std::snprintf(image_name, sizeof image_name, "/wd_data/lkB_000%02d.png", k + 1);
    std::snprintf(mask_name, sizeof mask_name, "/lkB_segmented/lkB_000%d_segmented.png", k);
    std::snprintf(camera, sizeof camera, "cam%02d", k);
    const Image image = ToRgb8(ReadImage(data + image_name));
    const Image truth = Binarize(ReadImage(data + mask_name));
    SilhouetteExtractor extractor(camera, "", [&image](int) { return image; }, 1, 0, SilhouetteOptions{});
    EXPECT_EQ(extractor.info().method, SilhouetteMethod::kGreen) << camera << ": a green screen, detected";
    MaskSummary summary;
    const Image mask = extractor.Extract(image, 0, &summary);
    const double iou = MaskIoU(mask, truth);
    std::printf("%-7s %-7s %9.3f %7.4f\n", camera, SilhouetteMethodName(extractor.info().method),
                extractor.info().greenness, iou);
    sum += iou;
    worst = std::min(worst, iou);
    tiles.push_back(DrawMaskOverlay(image, mask, 320, std::string(camera) + " IoU " + std::to_string(iou).substr(0, 5)));
  }
  std::printf("mean IoU %.4f, worst %.4f\n", sum / 20, worst);
  WriteImage(std::string(kSheetDir) + "/tsinghua_lkB.png", TileImages(tiles, 5));
  EXPECT_GE(sum / 20, 0.95);
}

// Frames of a video, decoded on demand (sequential reads are fast).
struct VideoFrames {
  explicit VideoFrames(const std::string& path) : reader(path) {}
  VideoReader reader;
  Image Read(int frame) { return reader.ReadFrame(frame); }
};

TEST(RealSilhouettes, UtrechtCleanPlateMasksAndVisualHull) {
  const std::string data = testing::SharedDataPath("real/utrecht_4cam");
  if (data.empty()) GTEST_SKIP() << "../shared/data/real/utrecht_4cam is absent";
  fs::create_directories(kSheetDir);
  const Rig rig = ImportCalibration(CalibFormat::kOpenCvXml, data);
  ASSERT_EQ(rig.size(), 4);
  const std::vector<int> frames = {0, 100, 200, 300, 400};
  // masks[f][c] in rig order.
  std::vector<std::vector<Image>> masks(frames.size(), std::vector<Image>(rig.size()));
  std::vector<Image> tiles;
  for (int c = 0; c < rig.size(); ++c) {
    const std::string folder = data + "/" + rig.cameras[c].name;
    // Plate statistics over 20 frames of the empty room's video.
    VideoFrames background(folder + "/background.avi");
    std::vector<Image> plates;
    for (int k = 0; k < 100; k += 5) plates.push_back(background.Read(k));
    VideoFrames video(folder + "/video.avi");
    const int num_frames = video.reader.num_frames();
    SilhouetteExtractor extractor(rig.cameras[c].name, plates, folder + "/background.avi",
                                  [&video](int k) { return video.Read(k); }, num_frames, 0, SilhouetteOptions{});
    EXPECT_EQ(extractor.info().method, SilhouetteMethod::kPlate);
    std::printf("%s: noise %.2f, threshold scale %.2f\n", rig.cameras[c].name.c_str(), extractor.info().noise_sigma,
                extractor.info().threshold_scale);
    for (std::size_t f = 0; f < frames.size(); ++f) {
      const Image image = video.Read(frames[f]);
      MaskSummary summary;
      masks[f][c] = extractor.Extract(image, frames[f], &summary);
      std::printf("  frame %3d: foreground %.2f%%, parts %d%s%s\n", frames[f], 100 * summary.foreground_fraction,
                  summary.parts, summary.touches_border ? ", touches border" : "", summary.empty ? ", EMPTY" : "");
      EXPECT_FALSE(summary.empty || summary.full) << rig.cameras[c].name << " frame " << frames[f];
      tiles.push_back(DrawMaskOverlay(image, masks[f][c], 320, rig.cameras[c].name + " frame " + std::to_string(frames[f])));
    }
  }
  const std::string sheet = std::string(kSheetDir) + "/utrecht_4cam.png";
  WriteImage(sheet, TileImages(tiles, static_cast<int>(frames.size())));
  std::printf("contact sheet (rows: cameras, columns: frames): %s\n", sheet.c_str());
  // Visual-hull consistency: the hull of three cameras' masks projected into the fourth.
  double sum = 0;
  int count = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    VisualHullOptions hull_options;
    const std::vector<double> ious = VisualHullConsistency(rig, masks[f], {}, hull_options);
    std::printf("frame %3d hull IoU:", frames[f]);
    for (double iou : ious) {
      std::printf(" %.3f", iou);
      sum += iou;
      ++count;
    }
    std::printf("\n");
  }
  // Reported, not asserted: about 0.61 with config.xml's calibration (the hull of 3 cameras is
  // loose, and the third-party calibration is itself inexact; see issue 2's notes).
  std::printf("mean hull IoU %.3f\n", sum / count);
  // A real seated person's plate masks carve a hull of one person's size (the check of
  // silhouette/multiview.h flags a larger one as background shared by the cameras).
  for (std::size_t f = 0; f < frames.size(); ++f) {
    std::vector<Image> checked = masks[f];
    const double volume = CheckMultiView(rig, &checked, {}, MultiViewOptions{})[0].hull_volume_m3;
    std::printf("frame %3d hull volume %.3f m^3\n", frames[f], volume);
    EXPECT_GT(volume, 0.03) << "frame " << frames[f];
    EXPECT_LT(volume, MultiViewOptions{}.max_hull_volume_m3) << "frame " << frames[f];
  }
  // The actor sits still: each camera's foreground must be stable across the frames.
  for (int c = 0; c < rig.size(); ++c)
    for (std::size_t f = 1; f < frames.size(); ++f)
      EXPECT_GE(MaskIoU(masks[f][c], masks[0][c]), 0.85) << rig.cameras[c].name << " frame " << frames[f];
}

TEST(RealSilhouettes, Pose2simLearnedBackgroundBestEffort) {
  const std::string data = testing::SharedDataPath("real/pose2sim_single");
  if (data.empty()) GTEST_SKIP() << "../shared/data/real/pose2sim_single is absent";
  fs::create_directories(kSheetDir);
  const std::vector<int> frames = {0, 33, 66, 99};
  std::vector<Image> tiles;
  int plausible = 0, total = 0;
  for (int c = 1; c <= 4; ++c) {
    char name[16];
    std::snprintf(name, sizeof name, "cam%02d", c);
    VideoFrames video(data + "/videos/" + name + ".mp4");
    const int num_frames = video.reader.num_frames();
    SilhouetteOptions options;
    options.method = SilhouetteMethod::kLearned;
    SilhouetteExtractor extractor(name, "", [&video](int k) { return video.Read(k); }, num_frames, 0, options);
    std::printf("%s: noise %.2f, threshold scale %.2f\n", name, extractor.info().noise_sigma,
                extractor.info().threshold_scale);
    for (int frame : frames) {
      const Image image = video.Read(frame);
      MaskSummary summary;
      const Image mask = extractor.Extract(image, frame, &summary);
      std::printf("  frame %3d: foreground %.2f%%, parts %d%s\n", frame, 100 * summary.foreground_fraction,
                  summary.parts, summary.touches_border ? ", touches border" : "");
      plausible += summary.foreground_fraction > 0.02 && summary.foreground_fraction < 0.4;
      ++total;
      tiles.push_back(DrawMaskOverlay(image, mask, 240, std::string(name) + " frame " + std::to_string(frame)));
    }
  }
  const std::string sheet = std::string(kSheetDir) + "/pose2sim_single.png";
  WriteImage(sheet, TileImages(tiles, static_cast<int>(frames.size())));
  std::printf("contact sheet (rows: cameras, columns: frames): %s\n", sheet.c_str());
  // Best effort: most masks have an actor-sized foreground.
  EXPECT_GE(plausible, total * 3 / 4);
}

// The learned person prior on the same footage: the whole performer in every camera, and
// nothing of the platform, the walls or the people around (the background model's masks above
// hold 30-47 % of each image).
TEST(RealSilhouettes, Pose2simPersonPriorFindsThePerformerOnly) {
  const std::string data = testing::SharedDataPath("real/pose2sim_single");
  if (data.empty()) GTEST_SKIP() << "../shared/data/real/pose2sim_single is absent";
  fs::create_directories(kSheetDir);
  const std::vector<int> frames = {0, 50, 99};
  std::vector<Image> tiles;
  for (int c = 1; c <= 4; ++c) {
    char name[16];
    std::snprintf(name, sizeof name, "cam%02d", c);
    VideoFrames video(data + "/videos/" + name + ".mp4");
    SilhouetteOptions options;
    options.method = SilhouetteMethod::kPerson;
    SilhouetteExtractor extractor(name, "", [&video](int k) { return video.Read(k); }, video.reader.num_frames(), 0,
                                  options);
    for (int frame : frames) {
      const Image image = video.Read(frame);
      MaskSummary summary;
      const Image mask = extractor.Extract(image, frame, &summary);
      std::printf("%s frame %3d: foreground %.2f%%, parts %d\n", name, frame, 100 * summary.foreground_fraction,
                  summary.parts);
      // The performer covers 5-7 % of these portrait images (measured at half resolution).
      EXPECT_GT(summary.foreground_fraction, 0.03) << name << " frame " << frame;
      EXPECT_LT(summary.foreground_fraction, 0.12) << name << " frame " << frame;
      EXPECT_LE(summary.parts, 2) << name << " frame " << frame;
      tiles.push_back(DrawMaskOverlay(image, mask, 240, std::string(name) + " frame " + std::to_string(frame)));
    }
  }
  const std::string sheet = std::string(kSheetDir) + "/pose2sim_person.png";
  WriteImage(sheet, TileImages(tiles, static_cast<int>(frames.size())));
  std::printf("contact sheet (rows: cameras, columns: frames): %s\n", sheet.c_str());
}

}  // namespace
}  // namespace confluent
