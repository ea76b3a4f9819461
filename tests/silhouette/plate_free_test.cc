// The plate-free background against a poster behind the actor that a person prior takes for the
// actor (BlazePose's segmentation does, for a poster in the shirt's colours): the poster is
// learned from the frames where the actor stands aside, which only the other cameras' hulls
// tell apart.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "core/cv_interop.h"
#include "silhouette/mask_cleanup.h"
#include "silhouette/plate_free.h"
#include "tests/silhouette/multiview_scene.h"
#include "tests/silhouette/synthetic_scene.h"

namespace confluent {
namespace {

// 8 cameras around an actor who stands in front of a poster (in camera 0's view) and, every
// fourth frame, steps aside. Camera 0's person regions always hold the poster.
struct PosterScene {
  static constexpr int kFrames = 24;
  Rig rig = testing::MakeRingRig(8, 160, 120);
  std::vector<std::vector<Image>> frames;
  std::vector<std::vector<PersonRegion>> people;
  Image poster;  // camera 0's poster (0/255)
  std::vector<Image> truth;  // camera 0's exact masks
  static bool Aside(int k) { return k % 4 == 3; }
  PosterScene() {
    frames.resize(rig.size());
    people.resize(rig.size());
    // The poster: the torso's box in camera 0 when the actor stands at the centre, grown by 6
    // pixels; red and black stripes, the red the shirt's.
    const Image torso = testing::RenderMask(rig.cameras[0], {testing::MakeActor(0, 0, 0)[2]});
    const cv::Rect box = cv::boundingRect(AsCvMat(torso)) + cv::Point(-6, -6) + cv::Size(12, 12);
    poster = Image(160, 120, 1);
    AsCvMat(poster)(box).setTo(255);
    for (int c = 0; c < rig.size(); ++c) {
      Image plate = testing::MakeTexturedPlate(160, 120, 11 + c);
      if (c == 0)
        for (int y = box.y; y < box.y + box.height; ++y)
          AsCvMat(plate)(cv::Rect(box.x, y, box.width, 1)).setTo(y % 6 < 3 ? cv::Scalar(200, 60, 50) : cv::Scalar(30, 30, 30));
      for (int k = 0; k < kFrames; ++k) {
        // Aside: 1.1 m across camera 0's view (it looks from the angle 0.3 rad, MakeRingRig).
        const double aside = Aside(k) ? 1.1 : 0.0;
        const auto actor = testing::MakeActor(-0.296 * aside, 0.955 * aside, 0.1 * (k % 10));
        Image frame = testing::RenderFrame(rig.cameras[c], actor, plate);
        testing::AddNoise(&frame, 2.0, 100 * c + k);
        frames[c].push_back(frame);
        if (c != 0) continue;
        const Image mask = testing::RenderMask(rig.cameras[c], actor);
        truth.push_back(mask);
        PersonRegion person;
        person.region = mask;
        cv::bitwise_or(AsCvMat(person.region), AsCvMat(poster), AsCvMat(person.region));
        person.core = mask;
        cv::erode(AsCvMat(mask), AsCvMat(person.core), cv::getStructuringElement(cv::MORPH_ELLIPSE, {5, 5}));
        person.within_reach = person.region;
        cv::dilate(AsCvMat(person.region), AsCvMat(person.within_reach),
                   cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
        person.height_px = 90;
        people[c].push_back(person);
      }
    }
  }
  // Fraction of the poster's uncovered pixels that camera 0's cleaned masks hold in the frames
  // where the actor stands aside.
  double PosterInMasks(const BackgroundModel& model) const {
    int total = 0, held = 0;
    for (int k = 0; k < kFrames; ++k) {
      if (!Aside(k)) continue;
      const Image mask = CleanMask(model.Classify(frames[0][k]), {});
      for (std::size_t i = 0; i < mask.data.size(); ++i) {
        if (poster.data[i] == 0 || truth[k].data[i] != 0) continue;
        ++total;
        held += mask.data[i] != 0;
      }
    }
    return static_cast<double>(held) / std::max(1, total);
  }
};

TEST(PlateFree, APosterThePersonPriorTakesForTheActorIsLearnedFromTheFramesWhereTheActorStandsAside) {
  const PosterScene scene;
  const auto learn = [&](int stable_free_samples) {
    PlateFreeOptions options;
    options.stable_free_samples = stable_free_samples;
    return LearnBackgroundsWithoutPlates(scene.rig, scene.frames, std::vector<BackgroundModel>(scene.rig.size()), {},
                                         {}, options, nullptr, 2, &scene.people)[0];
  };
  const double without = scene.PosterInMasks(learn(0)), with = scene.PosterInMasks(learn(3));
  std::printf("poster held by camera 0's masks when the actor stands aside: %.3f without, %.3f with the stable samples\n",
              without, with);
  EXPECT_GT(without, 0.5);  // never free: the poster is not learned
  EXPECT_LT(with, 0.05);
}

}  // namespace
}  // namespace confluent
