#include "silhouette/plate_free.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>

#include "core/cv_interop.h"
#include "core/error.h"
#include "core/parallel.h"
#include "silhouette/disk_morphology.h"

namespace confluent {

void PlateFreeOptions::Check() const {
  const std::string owner = "PlateFreeOptions.";
  RequireOption(iterations >= 0 && iterations <= 10, owner + "iterations", iterations, "in [0, 10]");
  RequireOption(occupancy_margin >= 0 && occupancy_margin <= 200, owner + "occupancy_margin", occupancy_margin,
                "in [0, 200]");
  RequireOption(head_room_m >= 0 && head_room_m <= 2, owner + "head_room_m", head_room_m, "in [0, 2]");
  RequireOption(head_room_near_top_m >= 0 && head_room_near_top_m <= 2, owner + "head_room_near_top_m",
                head_room_near_top_m, "in [0, 2]");
  RequireOption(background_colour > 0.5 && background_colour <= 1, owner + "background_colour", background_colour,
                "in (0.5, 1]");
  RequireOption(stable_free_samples >= 0 && stable_free_samples <= 1000, owner + "stable_free_samples",
                stable_free_samples, "in [0, 1000]");
  RequireOption(nearest_tolerance > 0 && nearest_tolerance <= 100, owner + "nearest_tolerance", nearest_tolerance,
                "in (0, 100]");
  multiview.Check();
}

namespace {

// `mask` grown by `per_1000` pixels per 1000 pixels of width.
cv::Mat Grow(const cv::Mat& mask, double per_1000) { return DilateByDisk(mask, ScaledRadius(per_1000, mask.cols)); }

// `image` (8-bit RGB) filled in over `region` (nonzero) from around it.
Image InpaintOver(const Image& image, const cv::Mat& region) {
  cv::Mat filled;
  cv::inpaint(AsCvMat(image), region, filled, 5.0, cv::INPAINT_TELEA);
  return ImageFromCvMat(filled);
}

// A model learned from `frames` with the given occupancy, its thresholds fitted to the first frames.
BackgroundModel Learn(const std::vector<Image>& frames, const std::vector<Image>& occupied, const Image& estimate,
                      const BackgroundModelOptions& options, const std::string& name) {
  BackgroundModel model = BackgroundModel::FromFrames(frames, options, name, occupied, estimate);
  if (options.auto_thresholds)
    model.AutoThreshold(std::vector<Image>(frames.begin(), frames.begin() + std::min<std::size_t>(frames.size(), 5)));
  return model;
}

// How far (RGB distance) a sample may lie from a colour and still be that colour: the noise
// (`sigma` grey levels, times the tolerance) plus 4% of the colour's brightness.
double ColourTolerance(const std::uint8_t* rgb, double sigma, const PlateFreeOptions& options) {
  const double brightness = std::sqrt(double(rgb[0]) * rgb[0] + double(rgb[1]) * rgb[1] + double(rgb[2]) * rgb[2]);
  return options.nearest_tolerance * sigma + 0.04 * brightness;
}

// Whether pixel i is free (unoccupied) in fewer than BackgroundModel::kMinFreeSamples samples.
bool TooFewFreeSamples(const std::vector<Image>& occupied, std::size_t i) {
  int free = 0;
  for (std::size_t k = 0; k < occupied.size() && free < BackgroundModel::kMinFreeSamples; ++k)
    free += occupied[k].data[i] == 0;
  return free < BackgroundModel::kMinFreeSamples;
}

// First estimate for one camera: where the samples ever differ from the temporal median (the
// actor passed, or stood), the background is the median image inpainted from around that
// region, and each pixel keeps the samples nearest to it.
// With `people`, the person's regions count as changed and as occupied too.
BackgroundModel FirstEstimate(const std::vector<Image>& frames, const BackgroundModelOptions& options,
                              const MaskCleanupOptions& cleanup, const PlateFreeOptions& plate_free,
                              const std::vector<PersonRegion>* people, const std::string& name, Image* estimate) {
  const BackgroundModel median = Learn(frames, {}, {}, options, name);
  const int w = median.width(), h = median.height();
  cv::Mat envelope = cv::Mat::zeros(h, w, CV_8U);
  for (const Image& frame : frames) {
    const Image mask = CleanMask(median.Classify(frame), cleanup);
    cv::bitwise_or(envelope, AsCvMat(mask), envelope);
  }
  std::vector<cv::Mat> person(frames.size());
  if (people != nullptr)
    for (std::size_t k = 0; k < frames.size(); ++k)
      if (!(*people)[k].region.empty()) {
        person[k] = Grow(AsCvMat((*people)[k].region), plate_free.occupancy_margin);
        cv::bitwise_or(envelope, person[k], envelope);
      }
  envelope = Grow(envelope, plate_free.occupancy_margin);
  const Image mean = median.MeanImage();
  *estimate = InpaintOver(mean, envelope);
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
    const double limit = nearest + ColourTolerance(e, sigma, plate_free);
    for (std::size_t k = 0; k < frames.size(); ++k)
      if (distance[k] > limit || (!person[k].empty() && person[k].data[i] != 0)) occupied[k].data[i] = 255;
  }
  return Learn(frames, occupied, *estimate, options, name);
}

// Colour histograms of the actor and of the background seen by one camera: how
// background-like a colour is (16 levels per channel).
class ColourPrior {
 public:
  // Adds the pixels of `frame` (8-bit RGB) where `actor` or `background` (1-channel) is set.
  void Add(const Image& frame, const cv::Mat& actor, const cv::Mat& background) {
    const std::size_t pixels = static_cast<std::size_t>(frame.width) * frame.height;
    for (std::size_t i = 0; i < pixels; i += 2) {
      if (actor.data[i]) {
        actor_[Bin(&frame.data[i * 3])] += 1;
        actor_total_ += 1;
      } else if (background.data[i]) {
        background_[Bin(&frame.data[i * 3])] += 1;
        background_total_ += 1;
      }
    }
  }
  // P(background | colour) with equal priors; 0.5 for a colour seen in neither.
  double BackgroundProbability(const std::uint8_t* rgb) const {
    if (actor_total_ <= 0 || background_total_ <= 0) return 0.5;
    const int bin = Bin(rgb);
    const double b = background_[bin] / background_total_ + 1e-5, a = actor_[bin] / actor_total_ + 1e-5;
    return b / (a + b);
  }

 private:
  static int Bin(const std::uint8_t* rgb) { return (rgb[0] >> 4) * 256 + (rgb[1] >> 4) * 16 + (rgb[2] >> 4); }
  std::vector<double> actor_ = std::vector<double>(4096, 0.0), background_ = std::vector<double>(4096, 0.0);
  double actor_total_ = 0, background_total_ = 0;
};

// The background estimate for one round: `first_estimate` inpainted over the pixels that
// `occupied` leaves with too few free samples (which take the estimate's colour). Outside
// the first estimate's "ever changed" envelope that estimate is the temporal median, which where
// the actor stood still is the actor: the surrounding background is the better guess.
Image InpaintNeverFree(const Image& first_estimate, const std::vector<Image>& occupied) {
  const std::size_t pixels = static_cast<std::size_t>(first_estimate.width) * first_estimate.height;
  cv::Mat never_free = cv::Mat::zeros(first_estimate.height, first_estimate.width, CV_8U);
  bool any = false;
  for (std::size_t i = 0; i < pixels; ++i)
    if (TooFewFreeSamples(occupied, i)) never_free.data[i] = 255, any = true;
  if (!any) return first_estimate;
  // Grown a little, so that the fill starts from the background around them and not from
  // their own rim.
  cv::dilate(never_free, never_free, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
  return InpaintOver(first_estimate, never_free);
}

// Frees, at each pixel that `occupied` leaves with too few free samples, the samples that
// `hull_occupied` (what the other cameras' strict hull claims) leaves free and whose colours
// agree with at least `options.stable_free_samples` - 1 others of them: the colour that keeps
// coming back whenever the actor is elsewhere is the background's.
void FreeStableSamplesOutsideHulls(const std::vector<Image>& frames, const std::vector<Image>& hull_occupied,
                                   double noise_sigma, const PlateFreeOptions& options, std::vector<Image>* occupied) {
  const int needed = options.stable_free_samples;
  if (needed <= 0) return;
  const std::size_t pixels = static_cast<std::size_t>(frames[0].width) * frames[0].height, samples = frames.size();
  const double sigma = std::max(1.0, noise_sigma);
  std::vector<std::size_t> candidates;
  std::vector<int> agreeing;
  for (std::size_t i = 0; i < pixels; ++i) {
    if (!TooFewFreeSamples(*occupied, i)) continue;
    candidates.clear();
    for (std::size_t k = 0; k < samples; ++k)
      if (hull_occupied[k].data[i] == 0) candidates.push_back(k);
    if (static_cast<int>(candidates.size()) < needed) continue;
    // The candidate with the most others of its colour, and those others.
    auto agree = [&](std::size_t a, std::size_t b) {
      const std::uint8_t* u = &frames[a].data[i * 3];
      const std::uint8_t* v = &frames[b].data[i * 3];
      double d2 = 0;
      for (int c = 0; c < 3; ++c) d2 += (double(u[c]) - v[c]) * (double(u[c]) - v[c]);
      const double limit = ColourTolerance(u, sigma, options);
      return d2 <= limit * limit;
    };
    agreeing.assign(candidates.size(), 0);
    for (std::size_t a = 0; a < candidates.size(); ++a)
      for (std::size_t b = a + 1; b < candidates.size(); ++b)
        if (agree(candidates[a], candidates[b])) ++agreeing[a], ++agreeing[b];
    const std::size_t best = std::max_element(agreeing.begin(), agreeing.end()) - agreeing.begin();
    if (agreeing[best] + 1 < needed) continue;
    for (std::size_t a = 0; a < candidates.size(); ++a)
      if (a == best || agree(candidates[best], candidates[a])) (*occupied)[candidates[a]].data[i] = 0;
  }
}

}  // namespace

std::vector<BackgroundModel> LearnBackgroundsWithoutPlates(const Rig& rig, const std::vector<std::vector<Image>>& frames,
                                                           std::vector<BackgroundModel> models,
                                                           const BackgroundModelOptions& background,
                                                           const MaskCleanupOptions& cleanup,
                                                           const PlateFreeOptions& options,
                                                           std::vector<std::string>* notes, int threads,
                                                           const std::vector<std::vector<PersonRegion>>* people) {
  options.Check();
  RequireOption(threads >= 1, "LearnBackgroundsWithoutPlates threads", threads, ">= 1");
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
  if (people != nullptr && static_cast<int>(people->size()) != n)
    throw UsageError("LearnBackgroundsWithoutPlates: the person regions are needed per camera");
  // Camera c's person regions, when it has one per sampled frame.
  auto person_of = [&](int c) -> const std::vector<PersonRegion>* {
    return people != nullptr && (*people)[c].size() == samples ? &(*people)[c] : nullptr;
  };
  std::vector<bool> learn(n, false);
  std::vector<Image> estimate(n);
  for (int c = 0; c < n; ++c) learn[c] = !frames[c].empty() && models[c].empty();
  ParallelFor(n, threads, [&](int c) {
    if (learn[c]) models[c] = FirstEstimate(frames[c], background, cleanup, options, person_of(c), rig.cameras[c].name,
                                &estimate[c]);
  });
  MultiViewOptions multiview = options.multiview;
  multiview.threads = threads;
  for (int round = 0; round < options.iterations; ++round) {
    std::vector<std::vector<Image>> occupied(n, std::vector<Image>(samples)),
        hull_occupied(n, std::vector<Image>(samples));
    std::vector<ColourPrior> priors(n);
    for (std::size_t k = 0; k < samples; ++k) {
      std::vector<Image> masks(n);
      ParallelFor(n, threads, [&](int c) {
        if (frames[c].empty() || models[c].empty()) return;
        masks[c] = CleanMask(models[c].Classify(frames[c][k]), cleanup);
        if (learn[c] && person_of(c) != nullptr)
          masks[c] = CleanMask(KeepNearPerson(masks[c], (*person_of(c))[k]), cleanup);
      });
      std::vector<Image> hulls, strict_hulls;
      HullUnderside underside;
      CheckMultiView(rig, &masks, learn, multiview, &hulls, &strict_hulls, &underside);
      ParallelFor(n, threads, [&](int c) {
        if (!learn[c]) return;
        // The occupancy: the mask, the tolerant hull and the strict one. The strict hull leaves
        // out the cameras whose masks it does not explain, so it keeps a still actor (a head, a
        // torso) that several cameras' masks miss, which the tolerant hull loses.
        cv::Mat occupancy = AsCvMat(masks[c]).clone();
        if (!hulls[c].empty()) cv::bitwise_or(occupancy, AsCvMat(hulls[c]), occupancy);
        if (!strict_hulls[c].empty()) cv::bitwise_or(occupancy, AsCvMat(strict_hulls[c]), occupancy);
        // Below, with a person prior, a pixel that the occupancy never leaves free may still be a
        // still background (a poster that the masks and the prior take for the actor) where the
        // strict hull leaves it free. The prior vouches for that hull: the first estimate took the
        // person's regions out of the background, so the masks, and the hull, hold even a still
        // person. (Without it a still leg is missing from the hull; and the room below and above
        // the hull, next, is too coarse: it covers the poster beside a side-on torso.)
        if (options.stable_free_samples > 0 && person_of(c) != nullptr)
          hull_occupied[c][k] = strict_hulls[c].empty() ? Image(frames[c][k].width, frames[c][k].height, 1)
                                                        : strict_hulls[c];
        // And what lies below the hull down to the floor: a performer who stands still is found
        // only where they move (a shirt, the arms), but their legs and feet are below.
        if (options.columns_to_floor)
          cv::bitwise_or(occupancy, AsCvMat(ProjectColumnsToFloor(rig.cameras[c], underside)), occupancy);
        // And the room above the hull's top: a still head that every camera's mask loses.
        if (options.head_room_m > 0)
          cv::bitwise_or(occupancy,
                         AsCvMat(ProjectColumnsAboveTop(rig.cameras[c], underside, options.head_room_near_top_m,
                                                        options.head_room_m)),
                         occupancy);
        // With a person prior: only what lies within reach of the person, and all of the person.
        const PersonRegion* person = person_of(c) != nullptr ? &(*person_of(c))[k] : nullptr;
        if (person != nullptr && !person->region.empty()) {
          cv::bitwise_and(occupancy, AsCvMat(person->within_reach), occupancy);
          cv::bitwise_or(occupancy, AsCvMat(person->region), occupancy);
        }
        occupied[c][k] = ImageFromCvMat(Grow(occupancy, options.occupancy_margin));
        // Colour samples: the actor where the mask and the hull agree (eroded), the background
        // well away from both.
        cv::Mat actor = AsCvMat(masks[c]).clone(), far;
        if (!hulls[c].empty()) cv::bitwise_and(actor, AsCvMat(hulls[c]), actor);
        cv::erode(actor, actor, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
        cv::bitwise_not(Grow(occupancy, 3 * options.occupancy_margin), far);
        priors[c].Add(frames[c][k], actor, far);
      });
    }
    ParallelFor(n, threads, [&](int c) {
      if (!learn[c]) return;
      // Lock-in breaker: where a ghost keeps the true background out of the free samples, a
      // clearly background-coloured sample counts as free, a clearly actor-coloured one never.
      const std::size_t pixels = static_cast<std::size_t>(frames[c][0].width) * frames[c][0].height;
      for (std::size_t k = 0; k < samples; ++k)
        for (std::size_t i = 0; i < pixels; ++i) {
          const double p = priors[c].BackgroundProbability(&frames[c][k].data[i * 3]);
          if (p >= options.background_colour) occupied[c][k].data[i] = 0;
          else if (p <= 1.0 - options.background_colour) occupied[c][k].data[i] = 255;
        }
      if (options.stable_free_samples > 0 && person_of(c) != nullptr)
        FreeStableSamplesOutsideHulls(frames[c], hull_occupied[c], models[c].noise_sigma(), options, &occupied[c]);
      models[c] = Learn(frames[c], occupied[c], InpaintNeverFree(estimate[c], occupied[c]), background,
                        rig.cameras[c].name);
    });
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
