#include "silhouette/plate_free.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>

#include "core/cv_interop.h"
#include "core/error.h"

namespace confluent {

void PlateFreeOptions::Check() const {
  const std::string owner = "PlateFreeOptions.";
  RequireOption(iterations >= 0 && iterations <= 10, owner + "iterations", iterations, "in [0, 10]");
  RequireOption(occupancy_margin >= 0 && occupancy_margin <= 200, owner + "occupancy_margin", occupancy_margin,
                "in [0, 200]");
  RequireOption(nearest_tolerance > 0 && nearest_tolerance <= 100, owner + "nearest_tolerance", nearest_tolerance,
                "in (0, 100]");
  multiview.Check();
}

namespace {

// `mask` grown by `per_1000` pixels per 1000 pixels of width.
cv::Mat Grow(const cv::Mat& mask, double per_1000) {
  const int radius = per_1000 > 0 ? std::max(1, static_cast<int>(std::lround(per_1000 * mask.cols / 1000.0))) : 0;
  if (radius == 0) return mask.clone();
  cv::Mat grown;
  cv::dilate(mask, grown, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1)));
  return grown;
}

// A model learned from `frames` with the given occupancy, its thresholds fitted to the first frames.
BackgroundModel Learn(const std::vector<Image>& frames, const std::vector<Image>& occupied, const Image& estimate,
                      const BackgroundModelOptions& options, const std::string& name) {
  BackgroundModel model = BackgroundModel::FromFrames(frames, options, name, occupied, estimate);
  if (options.auto_thresholds)
    model.AutoThreshold(std::vector<Image>(frames.begin(), frames.begin() + std::min<std::size_t>(frames.size(), 5)));
  return model;
}

// First estimate for one camera: where the samples ever differ from the temporal median (the
// actor passed, or stood), the background is the median image inpainted from around that
// region, and each pixel keeps the samples nearest to it.
BackgroundModel FirstEstimate(const std::vector<Image>& frames, const BackgroundModelOptions& options,
                              const MaskCleanupOptions& cleanup, const PlateFreeOptions& plate_free,
                              const std::string& name, Image* estimate) {
  const BackgroundModel median = Learn(frames, {}, {}, options, name);
  const int w = median.width(), h = median.height();
  cv::Mat envelope = cv::Mat::zeros(h, w, CV_8U);
  for (const Image& frame : frames) {
    const Image mask = CleanMask(median.Classify(frame), cleanup);
    cv::bitwise_or(envelope, AsCvMat(mask), envelope);
  }
  envelope = Grow(envelope, plate_free.occupancy_margin);
  const Image mean = median.MeanImage();
  cv::Mat filled;
  cv::inpaint(AsCvMat(mean), envelope, filled, 5.0, cv::INPAINT_TELEA);
  *estimate = ImageFromCvMat(filled);
  const std::size_t pixels = static_cast<std::size_t>(w) * h;
  std::vector<Image> occupied(frames.size(), Image(w, h, 1));
  const double sigma = std::max(1.0, median.noise_sigma());
  std::vector<double> distance(frames.size());
  for (std::size_t i = 0; i < pixels; ++i) {
    if (envelope.data[i] == 0) continue;
    const std::uint8_t* e = &estimate->data[i * 3];
    double nearest = 1e30;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const std::uint8_t* v = &frames[k].data[i * 3];
      double d2 = 0;
      for (int c = 0; c < 3; ++c) d2 += (double(v[c]) - e[c]) * (double(v[c]) - e[c]);
      distance[k] = std::sqrt(d2);
      nearest = std::min(nearest, distance[k]);
    }
    const double brightness = std::sqrt(double(e[0]) * e[0] + double(e[1]) * e[1] + double(e[2]) * e[2]);
    const double limit = nearest + plate_free.nearest_tolerance * sigma + 0.04 * brightness;
    for (std::size_t k = 0; k < frames.size(); ++k)
      if (distance[k] > limit) occupied[k].data[i] = 255;
  }
  return Learn(frames, occupied, *estimate, options, name);
}

}  // namespace

std::vector<BackgroundModel> LearnBackgroundsWithoutPlates(const Rig& rig, const std::vector<std::vector<Image>>& frames,
                                                           std::vector<BackgroundModel> models,
                                                           const BackgroundModelOptions& background,
                                                           const MaskCleanupOptions& cleanup,
                                                           const PlateFreeOptions& options,
                                                           std::vector<std::string>* notes) {
  options.Check();
  background.Check();
  cleanup.Check();
  const int n = rig.size();
  if (static_cast<int>(frames.size()) != n || static_cast<int>(models.size()) != n)
    throw UsageError("LearnBackgroundsWithoutPlates: frames and models are needed per camera");
  std::size_t samples = 0;
  for (int c = 0; c < n; ++c) {
    if (frames[c].empty()) continue;
    if (samples == 0) samples = frames[c].size();
    if (frames[c].size() != samples)
      throw UsageError("LearnBackgroundsWithoutPlates: every camera needs the same sampled instants");
  }
  if (samples < 3) throw InputError(n > 0 ? rig.cameras[0].name : "", "a learned background needs at least 3 frames");
  std::vector<bool> learn(n, false);
  std::vector<Image> estimate(n);
  for (int c = 0; c < n; ++c) {
    if (frames[c].empty() || !models[c].empty()) continue;
    learn[c] = true;
    models[c] = FirstEstimate(frames[c], background, cleanup, options, rig.cameras[c].name, &estimate[c]);
  }
  for (int round = 0; round < options.iterations; ++round) {
    std::vector<std::vector<Image>> occupied(n);
    std::vector<double> added(n, 0), removed(n, 0);
    for (std::size_t k = 0; k < samples; ++k) {
      std::vector<Image> masks(n);
      for (int c = 0; c < n; ++c)
        if (!frames[c].empty() && !models[c].empty()) masks[c] = CleanMask(models[c].Classify(frames[c][k]), cleanup);
      std::vector<Image> hulls;
      const std::vector<ViewConsistency> views = CheckMultiView(rig, &masks, learn, options.multiview, &hulls);
      for (int c = 0; c < n; ++c) {
        if (!learn[c]) continue;
        cv::Mat occupancy = AsCvMat(masks[c]).clone();
        if (!hulls[c].empty()) cv::bitwise_or(occupancy, AsCvMat(hulls[c]), occupancy);
        occupied[c].push_back(ImageFromCvMat(Grow(occupancy, options.occupancy_margin)));
        added[c] += views[c].added;
        removed[c] += views[c].removed;
      }
    }
    for (int c = 0; c < n; ++c)
      if (learn[c]) models[c] = Learn(frames[c], occupied[c], estimate[c], background, rig.cameras[c].name);
  }
  if (notes != nullptr)
    for (int c = 0; c < n; ++c)
      if (learn[c])
        notes->push_back(rig.cameras[c].name + ": background learned from " + std::to_string(samples) +
                         " frames without a plate (pixels the actor covers excluded through the other cameras, " +
                         std::to_string(options.iterations) + " round(s))");
  return models;
}

}  // namespace confluent
