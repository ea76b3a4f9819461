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
}

Image RefineMaskGrabCut(const Image& frame, const Image& mask, const Image& hull, const GrabCutRefineOptions& options) {
  options.Check();
  const cv::Mat m = AsCvMat(mask);
  if (cv::countNonZero(m) == 0) return mask;
  cv::Mat region = m.clone();
  if (!hull.empty()) cv::bitwise_or(region, AsCvMat(hull), region);
  const cv::Mat near = DilateByDisk(region, ScaledRadius(options.band, mask.width));
  cv::Mat core = m.clone();
  if (!hull.empty()) cv::bitwise_and(core, AsCvMat(hull), core);
  if (options.core > 0) core = ErodeByDisk(core, ScaledRadius(options.core, mask.width));
  // Work inside the band's bounding box (with a margin of certain background).
  cv::Rect box = cv::boundingRect(near);
  const int margin = 4;
  box = cv::Rect(box.x - margin, box.y - margin, box.width + 2 * margin, box.height + 2 * margin) &
        cv::Rect(0, 0, mask.width, mask.height);
  cv::Mat labels(box.size(), CV_8U, cv::Scalar(cv::GC_BGD));
  for (int y = 0; y < box.height; ++y)
    for (int x = 0; x < box.width; ++x) {
      const int gx = x + box.x, gy = y + box.y;
      std::uint8_t& label = labels.at<std::uint8_t>(y, x);
      if (core.at<std::uint8_t>(gy, gx)) label = cv::GC_FGD;
      else if (m.at<std::uint8_t>(gy, gx)) label = cv::GC_PR_FGD;
      else if (near.at<std::uint8_t>(gy, gx)) label = cv::GC_PR_BGD;
    }
  if (cv::countNonZero(labels == cv::GC_BGD) == 0 || cv::countNonZero((labels & 1) != 0) == 0) return mask;
  cv::Mat bgr;
  cv::cvtColor(AsCvMat(frame)(box), bgr, cv::COLOR_RGB2BGR);
  cv::Mat background_model, foreground_model;
  // grabCut seeds its colour models with k-means on the thread's random generator: a fixed seed
  // makes the result independent of which thread, and after what, refines this mask.
  cv::theRNG() = cv::RNG(0x2545F491u);
  cv::grabCut(bgr, labels, cv::Rect(), background_model, foreground_model, options.iterations, cv::GC_INIT_WITH_MASK);
  Image refined(mask.width, mask.height, 1);
  cv::Mat out = AsCvMat(refined);
  cv::Mat foreground = (labels == cv::GC_FGD) | (labels == cv::GC_PR_FGD);
  foreground.copyTo(out(box));
  return refined;
}

}  // namespace confluent
