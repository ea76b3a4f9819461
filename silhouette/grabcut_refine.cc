#include "silhouette/grabcut_refine.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/cv_interop.h"
#include "core/error.h"
#include "silhouette/disk_morphology.h"

namespace confluent {

void GrabCutRefineOptions::Check() const {
  const std::string owner = "GrabCutRefineOptions.";
  RequireOption(iterations >= 1 && iterations <= 10, owner + "iterations", iterations, "in [1, 10]");
  RequireOption(band > 0 && band <= 200, owner + "band", band, "in (0, 200]");
  RequireOption(core >= 0 && core <= 200, owner + "core", core, "in [0, 200]");
  RequireOption(retry_drop >= 0 && retry_drop <= 1, owner + "retry_drop", retry_drop, "in [0, 1]");
  RequireOption(retry_core >= 0 && retry_core <= 200, owner + "retry_core", retry_core, "in [0, 200]");
}

namespace {

// One graph cut with `core` as certain foreground.
Image Cut(const Image& frame, const cv::Mat& m, const cv::Mat& near, const cv::Mat& core, int iterations) {
  const int width = m.cols, height = m.rows;
  // Work inside the band's bounding box (with a margin of certain background).
  cv::Rect box = cv::boundingRect(near);
  const int margin = 4;
  box = cv::Rect(box.x - margin, box.y - margin, box.width + 2 * margin, box.height + 2 * margin) &
        cv::Rect(0, 0, width, height);
  cv::Mat labels(box.size(), CV_8U, cv::Scalar(cv::GC_BGD));
  for (int y = 0; y < box.height; ++y)
    for (int x = 0; x < box.width; ++x) {
      const int gx = x + box.x, gy = y + box.y;
      std::uint8_t& label = labels.at<std::uint8_t>(y, x);
      if (core.at<std::uint8_t>(gy, gx)) label = cv::GC_FGD;
      else if (m.at<std::uint8_t>(gy, gx)) label = cv::GC_PR_FGD;
      else if (near.at<std::uint8_t>(gy, gx)) label = cv::GC_PR_BGD;
    }
  Image refined(width, height, 1);
  if (cv::countNonZero(labels == cv::GC_BGD) == 0 || cv::countNonZero((labels & 1) != 0) == 0) {
    m.copyTo(AsCvMat(refined));
    return refined;
  }
  cv::Mat bgr;
  cv::cvtColor(AsCvMat(frame)(box), bgr, cv::COLOR_RGB2BGR);
  cv::Mat background_model, foreground_model;
  // grabCut seeds its colour models with k-means on the thread's random generator: a fixed seed
  // makes the result independent of which thread, and after what, refines this mask.
  cv::theRNG() = cv::RNG(0x2545F491u);
  cv::grabCut(bgr, labels, cv::Rect(), background_model, foreground_model, iterations, cv::GC_INIT_WITH_MASK);
  cv::Mat out = AsCvMat(refined);
  cv::Mat foreground = (labels == cv::GC_FGD) | (labels == cv::GC_PR_FGD);
  foreground.copyTo(out(box));
  return refined;
}

}  // namespace

Image RefineMaskGrabCut(const Image& frame, const Image& mask, const Image& hull, const GrabCutRefineOptions& options,
                        const Image& sure) {
  options.Check();
  const cv::Mat m = AsCvMat(mask);
  if (cv::countNonZero(m) == 0) return mask;
  cv::Mat region = m.clone();
  if (!hull.empty()) cv::bitwise_or(region, AsCvMat(hull), region);
  const cv::Mat near = DilateByDisk(region, ScaledRadius(options.band, mask.width));
  cv::Mat core = m.clone();
  if (!hull.empty()) cv::bitwise_and(core, AsCvMat(hull), core);
  if (options.core > 0) core = ErodeByDisk(core, ScaledRadius(options.core, mask.width));
  if (!sure.empty()) {
    if (sure.width != mask.width || sure.height != mask.height)
      throw UsageError("RefineMaskGrabCut: the sure foreground and the mask differ in size");
    cv::bitwise_or(core, AsCvMat(sure), core);
  }
  Image refined = Cut(frame, m, near, core, options.iterations);
  // A cut that gives up much of what the mask held inside the hull has taken a part of the actor
  // for the background (a shirt the wall's colour): cut again with the hull's deep inside as
  // certain foreground.
  if (!hull.empty() && options.retry_drop < 1) {
    const cv::Mat h = AsCvMat(hull);
    const double hull_area = std::max(1, cv::countNonZero(h));
    cv::Mat inside;
    cv::bitwise_and(m, h, inside);
    const double before = cv::countNonZero(inside) / hull_area;
    cv::bitwise_and(AsCvMat(refined), h, inside);
    const double after = cv::countNonZero(inside) / hull_area;
    if (after < before - options.retry_drop) {
      cv::bitwise_or(core, ErodeByDisk(h, ScaledRadius(options.retry_core, mask.width)), core);
      refined = Cut(frame, m, near, core, options.iterations);
    }
  }
  return refined;
}

int TakeBackKnownBackground(Image* refined, const Image& mask, const Image& frame, const BackgroundModel& model,
                            const Image& hull) {
  if (hull.empty()) return 0;
  const int w = refined->width, h = refined->height;
  for (const Image* image : {&mask, &frame, &hull})
    if (image->width != w || image->height != h)
      throw UsageError("TakeBackKnownBackground: the mask, frame, hull and refined mask differ in size");
  if (model.width() != w || model.height() != h)
    throw UsageError("TakeBackKnownBackground: the background model and the mask differ in size");
  Image labels;
  model.Classify(frame, &labels);
  int taken = 0;
  const std::size_t pixels = static_cast<std::size_t>(w) * h;
  for (std::size_t i = 0; i < pixels; ++i)
    if (refined->data[i] != 0 && mask.data[i] == 0 && hull.data[i] == 0 &&
        labels.data[i] == static_cast<std::uint8_t>(PixelClass::kBackground)) {
      refined->data[i] = 0;
      ++taken;
    }
  return taken;
}

}  // namespace confluent
