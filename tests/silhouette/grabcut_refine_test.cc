// The graph cut's boundary refinement against exact masks, and its second cut when the first
// takes a part of the actor for the background.

#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "core/cv_interop.h"
#include "core/error.h"
#include "silhouette/background_model.h"
#include "silhouette/grabcut_refine.h"
#include "tests/silhouette/synthetic_scene.h"

namespace confluent {
namespace {

using testing::Iou;

constexpr int kGrabWidth = 240, kGrabHeight = 240;
const cv::Scalar kWall(70, 90, 150), kFloor(110, 80, 55);

// A blue-grey wall over a brown floor, and a body: a head, a torso, red legs.
struct Body {
  Image frame{kGrabWidth, kGrabHeight, 3};
  Image truth{kGrabWidth, kGrabHeight, 1};
  Image torso{kGrabWidth, kGrabHeight, 1};
  explicit Body(const cv::Scalar& shirt) {
    cv::Mat image = AsCvMat(frame), mask = AsCvMat(truth), upper = AsCvMat(torso);
    image(cv::Rect(0, 0, kGrabWidth, 130)).setTo(kWall);
    image(cv::Rect(0, 130, kGrabWidth, kGrabHeight - 130)).setTo(kFloor);
    const auto draw = [&](const cv::Point& centre, const cv::Size& axes, const cv::Scalar& colour, bool is_torso) {
      cv::ellipse(image, centre, axes, 0, 0, 360, colour, cv::FILLED);
      cv::ellipse(mask, centre, axes, 0, 0, 360, cv::Scalar(255), cv::FILLED);
      if (is_torso) cv::ellipse(upper, centre, axes, 0, 0, 360, cv::Scalar(255), cv::FILLED);
    };
    draw({120, 95}, {32, 50}, shirt, true);
    draw({105, 175}, {12, 45}, cv::Scalar(170, 40, 40), false);
    draw({135, 175}, {12, 45}, cv::Scalar(170, 40, 40), false);
    draw({120, 35}, {14, 17}, cv::Scalar(220, 170, 140), false);
    cv::bitwise_and(upper, ~(mask - upper), upper);
    testing::AddNoise(&frame, 3.0, 5);
  }
};

TEST(GrabCutRefine, RemovesAGhostRimAndFillsAHole) {
  const Body body(cv::Scalar(200, 60, 50));  // a red shirt: the colours tell actor from wall
  Image mask = body.truth;
  cv::Mat m = AsCvMat(mask);
  cv::dilate(m, m, cv::getStructuringElement(cv::MORPH_ELLIPSE, {9, 9}));  // a 4-pixel ghost rim
  cv::circle(m, {120, 100}, 9, cv::Scalar(0), cv::FILLED);                  // a hole in the shirt
  Image hull = body.truth;
  cv::dilate(AsCvMat(hull), AsCvMat(hull), cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
  const Image refined = RefineMaskGrabCut(body.frame, mask, hull, {});
  std::printf("IoU %.3f -> %.3f\n", Iou(mask, body.truth), Iou(refined, body.truth));
  EXPECT_LT(Iou(mask, body.truth), 0.85);
  EXPECT_GE(Iou(refined, body.truth), 0.97);
}

// A shirt of the wall's colour that the mask holds only in stripes: the first cut takes the
// shirt for the wall and loses it; the second keeps the hull's deep inside.
TEST(GrabCutRefine, CutsAgainWhenTheFirstCutLosesWhatTheHullHolds) {
  const Body body(kWall + cv::Scalar(8, 6, -6));
  Image mask = body.truth;
  cv::Mat m = AsCvMat(mask);
  for (int y = 40; y < 150; y += 12) m(cv::Rect(0, y, kGrabWidth, 4)).setTo(0, AsCvMat(body.torso)(cv::Rect(0, y, kGrabWidth, 4)));
  Image hull = body.truth;
  cv::dilate(AsCvMat(hull), AsCvMat(hull), cv::getStructuringElement(cv::MORPH_ELLIPSE, {7, 7}));
  GrabCutRefineOptions once;
  once.retry_drop = 1;
  const Image first = RefineMaskGrabCut(body.frame, mask, hull, once);
  const Image again = RefineMaskGrabCut(body.frame, mask, hull, {});
  const auto torso_kept = [&](const Image& result) {
    int kept = 0, total = 0;
    for (std::size_t i = 0; i < result.data.size(); ++i) {
      total += body.torso.data[i] != 0;
      kept += body.torso.data[i] != 0 && result.data[i] != 0;
    }
    return static_cast<double>(kept) / total;
  };
  std::printf("torso kept: mask %.3f, one cut %.3f, with the second cut %.3f; IoU %.3f -> %.3f\n", torso_kept(mask),
              torso_kept(first), torso_kept(again), Iou(first, body.truth), Iou(again, body.truth));
  EXPECT_LT(torso_kept(first), 0.3);  // the failure the second cut is for
  EXPECT_GE(torso_kept(again), 0.8);
  EXPECT_GT(Iou(again, body.truth), Iou(first, body.truth) + 0.2);
}

// The same shirt, one cut only, with a person prior's core as certain foreground (the torso's
// inside): what the mask holds of it stays.
TEST(GrabCutRefine, SureForegroundStaysThroughTheCut) {
  const Body body(kWall + cv::Scalar(8, 6, -6));
  Image mask = body.truth;
  cv::Mat m = AsCvMat(mask);
  for (int y = 40; y < 150; y += 12) m(cv::Rect(0, y, kGrabWidth, 4)).setTo(0, AsCvMat(body.torso)(cv::Rect(0, y, kGrabWidth, 4)));
  GrabCutRefineOptions once;
  once.retry_drop = 1;
  Image sure = body.torso;
  cv::erode(AsCvMat(sure), AsCvMat(sure), cv::getStructuringElement(cv::MORPH_ELLIPSE, {9, 9}));
  cv::bitwise_and(AsCvMat(sure), m, AsCvMat(sure));
  const Image without = RefineMaskGrabCut(body.frame, mask, {}, once);
  const Image with = RefineMaskGrabCut(body.frame, mask, {}, once, sure);
  int lost_without = 0, lost_with = 0, sure_pixels = 0;
  for (std::size_t i = 0; i < sure.data.size(); ++i) {
    if (sure.data[i] == 0) continue;
    ++sure_pixels;
    lost_without += without.data[i] == 0;
    lost_with += with.data[i] == 0;
  }
  std::printf("sure pixels %d: lost by the cut %d, with them certain %d\n", sure_pixels, lost_without, lost_with);
  EXPECT_GT(lost_without, sure_pixels / 2);  // the failure the sure foreground is for
  EXPECT_EQ(lost_with, 0);
  EXPECT_THROW(RefineMaskGrabCut(body.frame, mask, {}, once, Image(10, 10, 1)), UsageError);
}

// A poster in the shirt's red beside the torso: the cut takes its near part for the shirt; the
// background model (here from a plate) knows it, and outside the hull it is taken back. What
// the cut filled inside the hull (a hole in the shirt) stays.
TEST(GrabCutRefine, WhatTheCutAddsThatTheBackgroundKnowsOutsideTheHullIsTakenBack) {
  const cv::Scalar red(200, 60, 50);
  const Body body(red);
  const cv::Rect poster_box(150, 55, 30, 70);  // touching the torso's right side
  Image plate(kGrabWidth, kGrabHeight, 3), frame = body.frame, poster(kGrabWidth, kGrabHeight, 1);
  AsCvMat(plate)(cv::Rect(0, 0, kGrabWidth, 130)).setTo(kWall);
  AsCvMat(plate)(cv::Rect(0, 130, kGrabWidth, kGrabHeight - 130)).setTo(kFloor);
  for (int y = poster_box.y; y < poster_box.y + poster_box.height; ++y)
    AsCvMat(plate)(cv::Rect(poster_box.x, y, poster_box.width, 1)).setTo(y % 8 < 5 ? red : cv::Scalar(30, 30, 30));
  testing::AddNoise(&plate, 3.0, 6);
  for (std::size_t i = 0; i < body.truth.data.size(); ++i) {
    const int x = static_cast<int>(i % kGrabWidth), y = static_cast<int>(i / kGrabWidth);
    if (body.truth.data[i] != 0 || !poster_box.contains({x, y})) continue;
    poster.data[i] = 255;
    for (int c = 0; c < 3; ++c) frame.data[i * 3 + c] = plate.data[i * 3 + c];
  }
  Image mask = body.truth;
  cv::circle(AsCvMat(mask), {110, 100}, 9, cv::Scalar(0), cv::FILLED);  // a hole in the shirt
  Image hull = body.truth;
  cv::dilate(AsCvMat(hull), AsCvMat(hull), cv::getStructuringElement(cv::MORPH_ELLIPSE, {5, 5}));
  const BackgroundModel model = BackgroundModel::FromPlates({plate}, {});
  const Image cut = RefineMaskGrabCut(frame, mask, hull, {});
  Image kept = cut;
  const int taken = TakeBackKnownBackground(&kept, mask, frame, model, hull);
  const auto count = [](const Image& a, const Image& b, bool b_set) {
    int n = 0;
    for (std::size_t i = 0; i < a.data.size(); ++i) n += a.data[i] != 0 && (b.data[i] != 0) == b_set;
    return n;
  };
  const int hole = count(body.truth, mask, false);
  std::printf("poster pixels in the cut %d, after taking back %d (%d taken); hole %d: filled %d, after %d\n",
              count(cut, poster, true), count(kept, poster, true), taken, hole, hole - count(body.truth, cut, false),
              hole - count(body.truth, kept, false));
  ASSERT_GT(count(cut, poster, true), 50);  // the failure this is for
  Image outside_hull = hull;
  cv::bitwise_not(AsCvMat(hull), AsCvMat(outside_hull));
  Image poster_outside = poster;
  cv::bitwise_and(AsCvMat(poster), AsCvMat(outside_hull), AsCvMat(poster_outside));
  EXPECT_EQ(count(kept, poster_outside, true), 0);
  EXPECT_EQ(count(body.truth, kept, false), count(body.truth, cut, false));  // the hole's filling stays
  EXPECT_EQ(TakeBackKnownBackground(&kept, mask, frame, model, {}), 0);       // no hull: nothing taken
  EXPECT_THROW(TakeBackKnownBackground(&kept, Image(10, 10, 1), frame, model, hull), UsageError);
}

TEST(GrabCutRefine, BadOptionsAreNamed) {
  GrabCutRefineOptions options;
  options.retry_drop = 1.5;
  try {
    options.Check();
    FAIL() << "no error";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("retry_drop"), std::string::npos);
  }
}

}  // namespace
}  // namespace confluent
